#!/usr/bin/env python3
"""The budget sweep's variants side by side, from scripts/eval_sweep.sh's output.

    scripts/sweep_table.py OUT [--variants paper,maturity,track,defer,...] [--condensed]

OUT holds one directory per variant (OUT/VARIANT/runs.csv and flags.txt, as
eval_sweep.sh --variants writes them; by default every such directory, paper
first, then by name). A variant's rows are labelled with its keepless_eval
flags from flags.txt; with --no-baselines among them only its keepless rows
count (the baselines are paper's). Prints, per sequence, one Markdown table: per kept
fraction F and per method of each variant, failed seeds, frames tracked,
ATE (mean ± sd over seeds, failed runs included), ATE over the original's
(paired: each run's original is the one of its own directory and seed, and
seeds whose original failed are left out of the ratios and shares, as
keepless_eval's own tables do),
local-BA observations and CPU seconds, map points and keyframes; then the
smallest F from which each method never failed, per F the method with the
lowest mean ATE among those with no failure, the accuracy-cost frontier:
the runs that no other beats on both ATE and local-BA observations, and how
ATE follows local-BA size (the correlation of log ATE and log observations,
each run over its seed's original, failed runs left out). A failed run (lost
tracking or a diverged BA) counts in every mean: its ATE is over all frames. --condensed prints
one cell per method (ATE over the original's, failed seeds, local-BA share) per
variant and F: a table per real sequence, and the synthetic back end's
trajectories together in one.
"""
import argparse
import csv
import math
import os
import statistics
import sys
from collections import defaultdict

METHODS = [("ours", "keepless"), ("random", "random"), ("longest_track", "longest track"), ("anms", "ANMS")]


def default_variants(out):
    if not os.path.isdir(out):
        sys.exit(f"sweep_table: {out} is not a directory")
    if os.path.exists(os.path.join(out, "flags.txt")):
        return ["."]  # one variant: eval_sweep.sh writes it into OUT itself
    found = sorted(d for d in os.listdir(out) if os.path.exists(os.path.join(out, d, "flags.txt")))
    if not found:
        sys.exit(f"sweep_table: {out} holds no variant (no flags.txt in it or its folders; scripts/eval_sweep.sh writes it)")
    return sorted(found, key=lambda v: v != "paper")


def variant_flags(out, variant):
    """The variant's keepless_eval flags (eval_sweep.sh's `eval:` line of flags.txt), keepless only or not."""
    path = os.path.join(out, variant, "flags.txt")
    if not os.path.exists(path):
        sys.exit(f"sweep_table: {path} is missing (scripts/eval_sweep.sh writes it)")
    flags = []
    with open(path) as f:
        for line in f:
            key, _, value = line.partition(":")
            if key == "eval":
                flags = value.split()
    return " ".join(w for w in flags if w != "--no-baselines"), "--no-baselines" in flags


def method_label(label, flags_text):
    """A method's row label: its name, then the variant's flags when it has any."""
    return f"{label}, {flags_text}" if flags_text else label


def load(out, variants, flags):
    # (sequence) -> (F, label) -> [rows]; originals by (variant directory, seed): a variant's flags
    # can change the original too (--no-keyframe-culling), and directories hold different seeds.
    table = defaultdict(lambda: defaultdict(list))
    originals = defaultdict(dict)
    titles = {}  # sequence -> its heading (the synthetic back end's trajectories say so)
    order = {}  # label -> (method, variant) rank: keepless's variants first, then each baseline's
    for variant in variants:
        path = os.path.join(out, variant, "runs.csv")
        if not os.path.exists(path):
            sys.exit(f"sweep_table: {path} is missing")
        text, keepless_only = flags[variant]
        with open(path) as f:
            for row in csv.DictReader(f):
                name, method, fraction = row["name"], row["variant"], float(row["target_fraction"])
                titles[name] = f"{name} (synthetic, {row['group']})" if row["kind"] == "trajectory" else name
                row["_pair"] = (variant, int(row["seed"]))
                if method == "original":
                    originals[name][row["_pair"]] = row
                    continue
                if method != "ours" and keepless_only:
                    continue
                label = method_label(dict(METHODS).get(method, method), text)
                table[name][(fraction, label)].append(row)
                order[label] = ([m for m, _ in METHODS].index(method) if method in dict(METHODS) else len(METHODS),
                                variants.index(variant))
    return table, originals, titles, order


def stat(rows, key):
    values = [float(r[key]) for r in rows]
    mean = statistics.mean(values)
    return mean, (statistics.stdev(values) if len(values) > 1 else 0.0)


def failed(row):
    return row["failed"] not in ("0", "", "null")


def paired(rows, originals, key):
    """Mean of `key` over the rows whose own original did not fail, over the same originals' mean."""
    both = [(r, originals[r["_pair"]]) for r in rows if r["_pair"] in originals and not failed(originals[r["_pair"]])]
    if not both:
        return float("nan")
    return statistics.mean(float(r[key]) for r, _ in both) / statistics.mean(float(o[key]) for _, o in both)


def seed_originals(originals):
    """One original per seed (the first directory's) for the original's own row."""
    by_seed = {}
    for (_, seed), row in sorted(originals.items()):
        by_seed.setdefault(seed, row)
    return list(by_seed.values())


def sequence_table(name, cells, originals, order):
    orig = seed_originals(originals)
    ate0, sd0 = stat(orig, "ate_m")
    lines = [f"#### {name}", "",
             "| F | method | failed | frames tracked | ATE (m) | / original | local-BA obs | local-BA CPU (s) |"
             " map points | keyframes |",
             "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|"]

    def row_line(fraction, label, rows):
        ate, sd = stat(rows, "ate_m")
        cpu, cpu_sd = stat(rows, "ba_cpu_s")
        fails = sum(failed(r) for r in rows)
        return (f"| {fraction} | {label} | {fails} / {len(rows)} | {stat(rows, 'frames_tracked')[0]:.1f} |"
                f" {ate:.4g} ± {sd:.2g} | {paired(rows, originals, 'ate_m'):.2f} | {stat(rows, 'observations')[0]:,.0f} |"
                f" {cpu:.2f} ± {cpu_sd:.2f} | {stat(rows, 'mps')[0]:,.0f} | {stat(rows, 'kfs')[0]:.0f} |")

    lines.append(row_line("–", "original", orig))
    labels = sorted({label for (_, label) in cells}, key=lambda label: order[label])
    fractions = sorted({f for (f, _) in cells})
    for fraction in fractions:
        for label in labels:
            if (fraction, label) in cells:
                lines.append(row_line(f"{fraction:.2f}", label, cells[(fraction, label)]))
    lines.append("")
    # Smallest F from which a method never failed (scanning down from the largest).
    safe = []
    for label in labels:
        smallest = None
        for fraction in reversed(fractions):
            rows = cells.get((fraction, label))
            if not rows or any(failed(r) for r in rows):
                break
            smallest = fraction
        safe.append(f"{label} {smallest:.1f}" if smallest is not None else f"{label}: never")
    lines.append("No failure from F = " + "; ".join(safe) + ".")
    lines.append("")
    best = []
    for fraction in fractions:
        ok = [(stat(rows, "ate_m")[0], label) for (f, label), rows in cells.items()
              if f == fraction and not any(failed(r) for r in rows)]
        best.append(f"F = {fraction:.1f}: " + (f"{min(ok)[1]} ({min(ok)[0]:.4g} m)" if ok else "none without failure"))
    lines.append(f"Lowest mean ATE without a failure (original {ate0:.4g} ± {sd0:.2g} m): " + "; ".join(best) + ".")
    lines.append("")
    # The accuracy-cost frontier: runs without a failure that no other such run
    # beats on both mean ATE and mean local-BA observations (the original included).
    points = [(stat(orig, "observations")[0], ate0, "original")]
    points += [(stat(rows, "observations")[0], stat(rows, "ate_m")[0], f"{label} at F = {f:.1f}")
               for (f, label), rows in cells.items() if not any(failed(r) for r in rows)]
    frontier = [p for p in points if not any(q[0] <= p[0] and q[1] <= p[1] and q != p for q in points)]
    lines.append("Accuracy-cost frontier (no failure; no other run has both fewer local-BA observations and a lower "
                 "mean ATE), by cost: " + "; ".join(f"{name} ({obs:,.0f} obs, {ate:.4g} m)"
                                                   for obs, ate, name in sorted(frontier)) + ".")
    lines.append("")
    # Does local-BA size buy accuracy here? Each run against its seed's original.
    pairs = [(math.log(float(r["observations"]) / float(originals[r["_pair"]]["observations"])),
              math.log(float(r["ate_m"]) / float(originals[r["_pair"]]["ate_m"])))
             for rows in cells.values() for r in rows
             if not failed(r) and r["_pair"] in originals and not failed(originals[r["_pair"]])]
    xs, ys = [x for x, _ in pairs], [y for _, y in pairs]
    if len(pairs) > 2 and len(set(xs)) > 1 and len(set(ys)) > 1:
        r = statistics.correlation(xs, ys)
        lines.append(f"ATE against local-BA observations, each run over its seed's original (no failure): "
                     f"correlation of the logs {r:.2f} over {len(pairs)} runs.")
        lines.append("")
    return "\n".join(lines)


def condensed_rows(cells, originals, variants, flags):
    """Per variant and F with a run: its title and one cell per method (ATE ratio, failed seeds, BA share)."""
    out = []
    for variant in variants:
        given = flags[variant][0]
        title = f"`{given}`" if given else "immediate (paper)"
        for fraction in sorted({f for (f, _) in cells}):
            row = []
            for method, label in METHODS:
                rows = cells.get((fraction, method_label(label, given)))
                if not rows:
                    row.append("–")
                    continue
                ratio, fails = paired(rows, originals, "ate_m"), sum(failed(r) for r in rows)
                text = f"{ratio:.2f}" if ratio < 10 else f"{ratio:.0f}"
                text = f"**{text}**" if fails == 0 else text
                row.append(f"{text} ({fails}/{len(rows)}), {100 * paired(rows, originals, 'observations'):.0f} %")
            if any(c != "–" for c in row):
                out.append(f"{title} | {fraction:.1f} | " + " | ".join(row))
    return out


CELL = ("Each cell: ATE over the original's (failed seeds), local-BA observations as a share of the original's, "
        "each run against its own seed's original; bold: no seed failed.")


def condensed_table(name, cells, originals, variants, flags):
    orig = seed_originals(originals)
    tracked = [r for r in orig if not failed(r)]
    lost = len(orig) - len(tracked)
    if tracked:
        ate0, obs0 = stat(tracked, "ate_m")[0], stat(tracked, "observations")[0]
        summary = (f"Original: ATE {ate0:.3g} m, {obs0:,.0f} local-BA observations, {len(tracked)} seeds"
                   f"{f' ({lost} more failed: left out of the ratios)' if lost else ''}.")
    else:  # no ratio can be formed: the cells show nan
        summary = f"Original: failed on all {lost} seeds, so there is no ratio."
    lines = [f"#### {name}", "",
             f"{summary} {CELL}",
             "", "| culling | F | " + " | ".join(m for _, m in METHODS) + " |", "|---|---:|" + "---|" * len(METHODS)]
    lines += [f"| {row} |" for row in condensed_rows(cells, originals, variants, flags)]
    lines.append("")
    return "\n".join(lines)


def synthetic_table(names, table, originals, titles, variants, flags):
    """The synthetic back end's trajectories in one table, a row per trajectory, variant and F."""
    lines = ["#### Synthetic back end", "", f"{CELL} The original's ATE per trajectory, mean over seeds.", "",
             "| trajectory (group) | original ATE (m) | culling | F | " + " | ".join(m for _, m in METHODS) + " |",
             "|---|---:|---|---:|" + "---|" * len(METHODS)]
    for name in names:
        ate0 = stat(seed_originals(originals[name]), "ate_m")[0]
        heading = titles[name].replace("synthetic, ", "")
        lines += [f"| {heading} | {ate0:.3g} | {row} |"
                  for row in condensed_rows(table[name], originals[name], variants, flags)]
    lines.append("")
    return "\n".join(lines)


def main(argv):
    parser = argparse.ArgumentParser(prog="sweep_table.py", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter, allow_abbrev=False)
    parser.add_argument("out", metavar="OUT")
    parser.add_argument("--variants")
    parser.add_argument("--condensed", action="store_true")
    args = parser.parse_args(argv[1:])
    out = args.out
    variants = args.variants.split(",") if args.variants else default_variants(out)
    flags = {variant: variant_flags(out, variant) for variant in variants}
    table, originals, titles, order = load(out, variants, flags)
    synthetic = [name for name in sorted(table) if "(synthetic" in titles[name]]
    for name in sorted(table):
        if not args.condensed:
            print(sequence_table(titles[name], table[name], originals[name], order))
        elif name not in synthetic:
            print(condensed_table(titles[name], table[name], originals[name], variants, flags))
    if args.condensed and synthetic:
        print(synthetic_table(synthetic, table, originals, titles, variants, flags))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
