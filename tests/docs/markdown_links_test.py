#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Every relative link in README.md and docs/*.md resolves: the file exists and, when the link
names an anchor, the target has a heading with that anchor (GitHub's rule: lower case, the
punctuation other than '-' and '_' dropped, spaces as '-', a repeated heading numbered -1, -2).
Usage: markdown_links_test.py SOURCE_DIR. Exits 1 naming every broken link."""
import pathlib
import re
import sys

LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
FENCE = re.compile(r"^\s*(```|~~~)")


def prose_lines(text, keep_code_spans=False):
    """(line number, line) outside fenced code blocks, inline code spans removed unless kept."""
    fenced = False
    for number, line in enumerate(text.splitlines(), 1):
        if FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            yield number, line if keep_code_spans else re.sub(r"`[^`]*`", "", line)


def anchor_of(heading):
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def anchors(path):
    found = set()
    seen = {}
    for _, line in prose_lines(path.read_text(encoding="utf-8"), keep_code_spans=True):
        match = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if not match:
            continue
        base = anchor_of(match.group(1).replace("`", ""))
        count = seen.get(base, 0)
        seen[base] = count + 1
        found.add(base if count == 0 else f"{base}-{count}")
    return found


def broken_links(source_dir):
    pages = [source_dir / "README.md"] + sorted((source_dir / "docs").glob("*.md"))
    problems = []
    for page in pages:
        for number, line in prose_lines(page.read_text(encoding="utf-8")):
            for target in LINK.findall(line):
                if re.match(r"^[a-z][a-z0-9+.-]*:", target):
                    continue  # https:, mailto: ...: not checked offline
                path_part, _, anchor = target.partition("#")
                where = f"{page.relative_to(source_dir)}:{number}: {target}"
                linked = (page.parent / path_part).resolve() if path_part else page
                if not linked.exists():
                    problems.append(f"{where}: no file {path_part}")
                elif anchor and linked.suffix == ".md" and anchor not in anchors(linked):
                    problems.append(f"{where}: {path_part or page.name} has no heading #{anchor}")
    return pages, problems


def main():
    if len(sys.argv) != 2:
        print("usage: markdown_links_test.py SOURCE_DIR", file=sys.stderr)
        return 2
    pages, problems = broken_links(pathlib.Path(sys.argv[1]).resolve())
    for problem in problems:
        print(problem)
    print(f"{len(pages)} pages, {len(problems)} broken links")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
