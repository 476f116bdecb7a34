#!/usr/bin/env python3
"""Every code block marked `<!-- snippet: FILE#NAME -->` in README.md and docs/
equals the region of FILE between its `snippet-begin: NAME` and
`snippet-end: NAME` lines (indentation removed), so the documentation shows
code that the examples build and run.

    check_snippets.py [REPO_ROOT]
"""
import pathlib
import re
import sys
import textwrap

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent)
MARK = re.compile(r"<!--\s*snippet:\s*([^#\s]+)#(\S+)\s*-->")


def region(path, name):
    lines = path.read_text(encoding="utf-8").split("\n")
    begin = [i for i, l in enumerate(lines) if re.search(rf"snippet-begin:\s*{re.escape(name)}\s*$", l)]
    end = [i for i, l in enumerate(lines) if re.search(rf"snippet-end:\s*{re.escape(name)}\s*$", l)]
    if len(begin) != 1 or len(end) != 1 or end[0] <= begin[0]:
        return None
    return textwrap.dedent("\n".join(lines[begin[0] + 1:end[0]])).strip("\n")


errors, checked = [], 0
pages = [root / "README.md"] + sorted((root / "docs").rglob("*.md"))
for page in pages:
    lines = page.read_text(encoding="utf-8").split("\n")
    for i, line in enumerate(lines):
        m = MARK.match(line.strip())
        if not m:
            continue
        where = f"{page.relative_to(root)}:{i + 1}"
        j = i + 1
        while j < len(lines) and not lines[j].strip():
            j += 1
        if j >= len(lines) or not lines[j].startswith("```"):
            errors.append(f"{where}: the snippet marker is not followed by a code block")
            continue
        k = j + 1
        while k < len(lines) and not lines[k].startswith("```"):
            k += 1
        shown = "\n".join(lines[j + 1:k]).strip("\n")
        source = root / m.group(1)
        if not source.is_file():
            errors.append(f"{where}: {m.group(1)} does not exist")
            continue
        expected = region(source, m.group(2))
        if expected is None:
            errors.append(f"{where}: {m.group(1)} has no single region '{m.group(2)}'")
        elif shown != expected:
            errors.append(f"{where}: differs from {m.group(1)}#{m.group(2)}; paste the region again")
        checked += 1

for e in errors:
    print(e, file=sys.stderr)
print(f"check_snippets: {checked} snippets checked, {len(errors)} problems")
sys.exit(1 if errors or checked == 0 else 0)
