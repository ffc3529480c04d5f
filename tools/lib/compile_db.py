# SPDX-License-Identifier: Apache-2.0
"""The build's compilation database as clang-tidy needs it: one entry per project source.

The GCC-only flags clang does not know are dropped, and each unity batch
(Unity/unity_N_cxx.cxx, which #includes its target's sources) is listed as the sources it
includes, each with the batch's command.

    compile_db.py BUILD_DB OUT_DB    writes the copy clang-tidy reads (-p OUT_DB's folder)
"""

import json
import os
import re
import sys

GCC_ONLY = {"-fno-gnu-unique"}
UNITY_BATCH = re.compile(r"/Unity/unity_[0-9]+_(cxx|c)\.(cxx|c)$")
INCLUDED = re.compile(r'^#include "(.+)"$', re.MULTILINE)


def lint_entries(build_db):
    """The entries of build_db, unity batches expanded, GCC-only flags dropped."""
    with open(build_db, encoding="utf-8") as f:
        entries = json.load(f)
    out = []
    for e in entries:
        e["command"] = " ".join(w for w in e["command"].split(" ") if w not in GCC_ONLY)
        if not UNITY_BATCH.search(e["file"]):
            out.append(e)
            continue
        with open(e["file"], encoding="utf-8") as batch:
            sources = INCLUDED.findall(batch.read())
        for source in sources:
            out.append({"directory": e["directory"], "file": source,
                        "command": e["command"].replace(e["file"], source)})
    return out


def load(lint_db):
    """The entries of a database lint_entries wrote."""
    with open(lint_db, encoding="utf-8") as f:
        return json.load(f)


def by_source(entries, root, tracked):
    """{path relative to root: entry} for the tracked sources (not generated ones)."""
    sources = {}
    for e in entries:
        path = os.path.relpath(os.path.normpath(os.path.join(e["directory"], e["file"])), root)
        if path in tracked:
            sources.setdefault(path, e)
    return sources


def main(argv):
    if len(argv) != 3:
        sys.exit("usage: compile_db.py BUILD_DB OUT_DB")
    with open(argv[2], "w", encoding="utf-8") as f:
        json.dump(lint_entries(argv[1]), f, indent=1)


if __name__ == "__main__":
    main(sys.argv)
