#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Reports C++ functions longer than a limit, counted in lines from the opening brace of the
body to the closing one (lambdas and local classes count as part of the function they are in).

    function_length.py [--max N] PATH...    PATH: a .cpp/.hpp file, or a directory searched
                                            for them

Prints "file:line: N lines (limit N): <signature>" per function over the limit and exits 1 if
there is one, else 0. A body is a brace that follows a parameter list: ')' and then any of
const, noexcept, override, final, mutable, a trailing return type or a constructor's member
initializers. Comments, string and character literals are blanked first.
"""
import argparse
import pathlib
import re
import sys

_QUALIFIED_CLOSE = re.compile(
    r"\)\s*(?:(?:const|noexcept|override|final|mutable|&&|&)\s*|->\s*[\w:<>,\s*&]+)*$")
# ") : member(value), other{value}" before a constructor's body.
_INITIALIZERS = re.compile(r"\)\s*(?:noexcept\s*)?:\s*[\w:]+\s*[({]", re.S)


def blank(source):
    """The source with comments, string and character literals replaced by spaces (newlines kept)."""
    out = []
    i = 0
    n = len(source)
    while i < n:
        c = source[i]
        two = source[i:i + 2]
        if two == "//":
            j = source.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif two == "/*":
            j = source.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", source[i:j]))
            i = j
        elif c == 'R' and source[i + 1:i + 2] == '"':
            m = re.match(r'R"([^(\s]*)\(', source[i:])
            if not m:
                out.append(c)
                i += 1
                continue
            end = source.find(")" + m.group(1) + '"', i)
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", source[i:j]))
            i = j
        elif c in "\"'":
            if c == "'" and i > 0 and (source[i - 1].isalnum() or source[i - 1] == "_"):
                out.append(" ")  # a digit separator: 1'000
                i += 1
                continue
            j = i + 1
            while j < n and source[j] != c and source[j] != "\n":
                j += 2 if source[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(c + " " * (j - i - 2) + c if j - i >= 2 else " " * (j - i))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def long_functions(path, limit):
    text = blank(path.read_text(encoding="utf-8", errors="replace"))
    found = []
    stack = []  # per open brace: (line, is_function)
    line = 1
    head_start = 0  # where the text before the next brace began
    for i, c in enumerate(text):
        if c == "\n":
            line += 1
        elif c == ";":
            head_start = i + 1
        elif c == "{":
            head = text[head_start:i].strip()
            in_function = any(entry[1] for entry in stack)
            is_function = not in_function and (
                _QUALIFIED_CLOSE.search(head) is not None or _INITIALIZERS.search(head) is not None)
            stack.append((line, is_function, " ".join(head.split())[-70:]))
            head_start = i + 1
        elif c == "}":
            head_start = i + 1
            if not stack:
                continue
            start, is_function, signature = stack.pop()
            if is_function and line - start + 1 > limit:
                found.append((start, line - start + 1, signature))
    return found


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max", type=int, default=80, help="longest allowed (lines)")
    parser.add_argument("paths", nargs="+")
    args = parser.parse_args(argv)
    files = []
    for p in map(pathlib.Path, args.paths):
        if p.is_dir():
            files += sorted(f for f in p.rglob("*") if f.suffix in (".cpp", ".hpp", ".h", ".cc"))
        elif p.is_file():
            files.append(p)
        else:
            print(f"{p}: no such file or directory", file=sys.stderr)
            return 2
    count = 0
    for f in files:
        for start, lines, signature in long_functions(f, args.max):
            print(f"{f}:{start}: {lines} lines (limit {args.max}): {signature}")
            count += 1
    print(f"{len(files)} files, {count} functions over {args.max} lines")
    return 1 if count else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
