# SPDX-License-Identifier: Apache-2.0
"""The project's #include graph, as each translation unit of a compilation database sees it.

Every #include is taken, whatever #if surrounds it: for a lint cache and a layering check,
counting a header that is not compiled is safe, missing one that is would not be. A header
is resolved as the compiler would look for it: a quoted one first next to the file that
includes it, then along the unit's -I/-iquote directories in order. Only headers inside the
repository or the build tree are followed; system headers are not.
"""

import functools
import os
import re
import shlex

INCLUDE = re.compile(r'^[ \t]*#[ \t]*include[ \t]*([<"])([^>"]+)[>"]', re.MULTILINE)


@functools.lru_cache(maxsize=None)
def read_includes(path):
    """The (is_quoted, name) pairs of the #include lines of path (read once a run)."""
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            text = f.read()
    except OSError:
        text = ""
    return tuple((quote == '"', name) for quote, name in INCLUDE.findall(text))


def include_dirs(command, directory):
    """The -I and -iquote directories of a compile command, absolute, in order."""
    words = shlex.split(command)
    dirs = []
    i = 0
    while i < len(words):
        word = words[i]
        for flag in ("-I", "-iquote"):
            if word == flag and i + 1 < len(words):
                dirs.append(words[i + 1])
                i += 1
            elif word.startswith(flag) and len(word) > len(flag):
                dirs.append(word[len(flag):])
        i += 1
    return [os.path.normpath(os.path.join(directory, d)) for d in dirs]


class Resolver:
    """Resolves #include names of one translation unit to files under the given roots."""

    def __init__(self, dirs, roots):
        self.dirs = dirs
        self.roots = tuple(os.path.join(r, "") for r in roots)

    def resolve(self, including, quoted, name):
        search = ([os.path.dirname(including)] if quoted else []) + self.dirs
        for d in search:
            candidate = os.path.normpath(os.path.join(d, name))
            if candidate.startswith(self.roots) and os.path.isfile(candidate):
                return candidate
        return None


def unit_edges(source, resolver):
    """Every (including file, included file) edge reachable from source, and the files."""
    edges = []
    seen = {source}
    stack = [source]
    while stack:
        current = stack.pop()
        for quoted, name in read_includes(current):
            target = resolver.resolve(current, quoted, name)
            if target is None:
                continue
            edges.append((current, target))
            if target not in seen:
                seen.add(target)
                stack.append(target)
    return edges, seen
