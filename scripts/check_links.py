#!/usr/bin/env python3
"""README.md and docs/**/*.md: every relative link resolves to a file or
folder of the repository, every #anchor to a heading of its page, and no page
names internal things (issue numbers, machine paths, who shared the machine).

    check_links.py [REPO_ROOT]
"""
import pathlib
import re
import sys

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parent.parent)
pages = [root / "README.md", root / "CHANGELOG.md"] + sorted((root / "docs").rglob("*.md"))
LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
INTERNAL = re.compile(r"issue [0-9]|/work/|/root/|\bsession|engineers", re.IGNORECASE)


def slug(text):
    text = re.sub(r"`([^`]*)`", r"\1", text)              # code spans keep their text
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)  # links keep their label
    text = re.sub(r"[^\w\- ]", "", text.strip().lower())
    return text.replace(" ", "-")


def prose(path):
    """(line number, text) outside fenced code blocks."""
    fence = False
    for n, line in enumerate(path.read_text(encoding="utf-8").split("\n"), 1):
        if line.lstrip().startswith("```"):
            fence = not fence
            continue
        if not fence:
            yield n, line


anchors = {}


def anchors_of(path):
    if path not in anchors:
        seen, found = {}, set()
        for _, line in prose(path):
            m = re.match(r"^#{1,6} (.*?)\s*#*$", line)
            if m:
                s = slug(m.group(1))
                if s in seen:
                    seen[s] += 1
                    s = f"{s}-{seen[s]}"
                else:
                    seen[s] = 0
                found.add(s)
        anchors[path] = found
    return anchors[path]


errors = []
links = 0
for page in pages:
    rel = page.relative_to(root)
    for n, line in enumerate(page.read_text(encoding="utf-8").split("\n"), 1):  # code blocks too
        if INTERNAL.search(line):
            errors.append(f"{rel}:{n}: internal reference: {INTERNAL.search(line).group(0)!r}")
    for n, line in prose(page):
        for target in LINK.findall(re.sub(r"`[^`]*`", "", line)):
            if re.match(r"^[a-z][a-z0-9+.-]*:", target):
                continue  # https:, mailto: ...
            links += 1
            path_part, _, anchor = target.partition("#")
            dest = (page.parent / path_part).resolve() if path_part else page
            if path_part and not dest.exists():
                errors.append(f"{rel}:{n}: {target}: no such file")
                continue
            if anchor and dest.suffix == ".md" and anchor not in anchors_of(dest):
                errors.append(f"{rel}:{n}: {target}: no heading with anchor #{anchor}")

for e in errors:
    print(e, file=sys.stderr)
print(f"check_links: {len(pages)} pages, {links} relative links, {len(errors)} problems")
sys.exit(1 if errors else 0)
