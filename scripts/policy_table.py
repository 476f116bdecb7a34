#!/usr/bin/env python3
"""README's policy table from several keepless_eval --out directories.

    scripts/policy_table.py "paper, window=eval_paper04" "information, floor 30=eval_info04" ...
    scripts/policy_table.py --vo "information=vo_7s+vo_k00+vo_k06" ...

Each LABEL=DIR is one keepless_eval run (one policy, one kept fraction; DIR+DIR
joins runs of one policy on different inputs); its runs.csv holds every seed's
run. --vo prints one row per policy and real-VO sequence instead. Per group (TUM, EuRoC = MH + V, KITTI, the
real images) each variant's ATE is a ratio to the original's mean over
seeds, averaged over the group's inputs, as keepless_eval's group table does.
Prints one Markdown table: ours / original, and ours against random and
longest-track-first at the same count (negative: ours lower), with the seeds
on which ours was lower, then the groups on which each comparison held.
"""
import csv
import os
import statistics
import sys
from collections import defaultdict

GROUPS = [("TUM", {"tum"}), ("EuRoC", {"euroc_mh", "euroc_v"}), ("KITTI", {"kitti"}),
          ("real images", {"kitti_images"})]  # BAL has no ground truth: its original is the reference


def load(directories):
    runs = defaultdict(lambda: defaultdict(dict))  # input -> variant -> seed -> row
    group = {}
    for directory in directories.split("+"):
        with open(os.path.join(directory, "runs.csv")) as f:
            for row in csv.DictReader(f):
                runs[row["name"]][row["variant"]][int(row["seed"])] = row
                group[row["name"]] = row["group"]
    return runs, group


def mean_ate(rows):
    return statistics.mean(float(r["ate_m"]) for r in rows.values())


def vo_rows(label, directories):
    runs, _ = load(directories)
    for name, v in sorted(runs.items()):
        ours = v["ours"]
        m = next(iter(ours.values()))["M"]
        mp = statistics.mean(100.0 * float(r["mps"]) / float(v["original"][s]["mps"]) for s, r in ours.items())
        ate = {k: mean_ate(v[k]) for k in ("original", "ours", "random", "longest_track", "anms") if v[k]}
        sd = statistics.stdev(float(r["ate_m"]) for r in ours.values()) if len(ours) > 1 else 0.0
        below = lambda b: sum(float(r["ate_m"]) < float(v[b][s]["ate_m"]) for s, r in ours.items() if s in v[b])
        vs = lambda b: "%+.0f %% (%d/%d)" % (100 * (ate["ours"] / ate[b] - 1), below(b), len(ours))
        print("| %s | %s | %s | %.0f | %.4f | %.4f ± %.4f | %.4f | %.4f | %.4f | %s | %s | %+.0f %% |" % (
            label, name, m, mp, ate["original"], ate["ours"], sd, ate["random"], ate["longest_track"], ate["anms"],
            vs("random"), vs("longest_track"), 100 * (ate["ours"] / ate["original"] - 1)))


def summarize(directory):
    runs, group = load(directory)
    out = {}
    for label, members in GROUPS:
        names = [n for n in runs if group[n] in members]
        if not names:
            continue
        ratio = defaultdict(list)
        below = defaultdict(int)
        seeds = 0
        mp = []
        for n in names:
            v = runs[n]
            orig = statistics.mean(float(r["ate_m"]) for r in v["original"].values())
            ours = v["ours"]
            for name in ("ours", "random", "longest_track"):
                if v[name]:
                    ratio[name].append(statistics.mean(float(r["ate_m"]) for r in v[name].values()) / orig)
            for s, r in ours.items():
                seeds += 1
                mp.append(100.0 * float(r["mps"]) / float(v["original"][s]["mps"]))
                for name in ("random", "longest_track"):
                    if s in v[name] and float(r["ate_m"]) < float(v[name][s]["ate_m"]):
                        below[name] += 1
        out[label] = {k: statistics.mean(x) for k, x in ratio.items()}
        out[label].update(below=below, seeds=seeds, mp=statistics.mean(mp), inputs=len(names))
    return out


def main(argv):
    vo = len(argv) > 1 and argv[1] == "--vo"
    args = argv[2:] if vo else argv[1:]
    if not args or any("=" not in a for a in args):
        sys.exit(__doc__)
    if vo:
        print("| policy | sequence | M | MP % | ATE original (m) | ours | random | longest track | ANMS | "
              "ours vs random (seeds lower) | vs longest | vs original |")
        print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        for a in args:
            vo_rows(*a.split("=", 1))
        return
    rows = [(a.split("=", 1)[0], summarize(a.split("=", 1)[1])) for a in args]
    present = [g for g, _ in GROUPS if any(g in r for _, r in rows)]
    print("| policy | " + " | ".join(present) + " | lower than random | lower than longest | within 10 % of original |")
    print("|---|" + "---|" * len(present) + "---:|---:|---:|")
    for label, r in rows:
        cells, beat_r, beat_l, within = [], 0, 0, 0
        for g in present:
            if g not in r:
                cells.append("–")
                continue
            x = r[g]
            pct = lambda b: "–" if b not in x else "%+.0f %% (%d/%d)" % (100 * (x["ours"] / x[b] - 1), x["below"][b], x["seeds"])
            cells.append("MP %.0f %%: **%.2f**×; vs random %s; vs longest %s" % (x["mp"], x["ours"], pct("random"), pct("longest_track")))
            beat_r += "random" in x and x["ours"] < x["random"]
            beat_l += "longest_track" in x and x["ours"] < x["longest_track"]
            within += x["ours"] <= 1.1
        n = sum(g in r for g, _ in GROUPS)
        print("| %s | %s | %d of %d | %d of %d | %d of %d |" % (label, " | ".join(cells), beat_r, n, beat_l, n, within, n))


if __name__ == "__main__":
    main(sys.argv)
