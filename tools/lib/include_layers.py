# SPDX-License-Identifier: Apache-2.0
"""Checks that every #include of the project points down or across its floors.

The floors of docs/architecture.md ("Floors"), lowest first. A file may include files of its
own floor and the floors below, never one above; besides:
  - a header under a folder's src/ is that folder's own (core's src/ headers may also be
    read by the tests under tests/, which test the daemon's parts one by one);
  - a plugin's public headers (plugins/<kind>/<name>/include/) expose only the plugin: they
    include core, the shared libraries and the plugin's own headers.

    include_layers.py REPO LINT_DB    prints each offending include; exit 1 if there is one
"""

import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import compile_db  # noqa: E402
import include_graph  # noqa: E402

# (folder, floor): the longest matching folder decides a file's floor.
FLOORS = [
    ("core/", 0),
    # Shared libraries: the statistics, the tests' support code (fakes, the allocation
    # guard, DDS helpers) and the two validation robots, which share no code with the rest.
    ("libs/", 1),
    ("tests/support/", 1),
    ("tests/second_robot/", 1),
    ("tests/independent_robot/", 1),
    ("plugins/", 2),
    ("tools/", 3),
    ("tests/", 4),
    ("examples/", 4),
]
FLOOR_NAMES = {0: "core", 1: "shared libraries", 2: "plugins", 3: "tools", 4: "tests"}


def floor_of(path):
    best = None
    for folder, floor in FLOORS:
        if path.startswith(folder) and (best is None or len(folder) > len(best[0])):
            best = (folder, floor)
    return None if best is None else best[1]


def private_owner(path):
    """The folder whose src/ holds path, if it does."""
    head, sep, _ = path.rpartition("/src/")
    return head + "/" if sep else None


def plugin_of(path):
    parts = path.split("/")
    return "/".join(parts[:3]) + "/" if parts[0] == "plugins" and len(parts) > 3 else None


def problem(including, included):
    """Why including may not include included, or None."""
    low, high = floor_of(included), floor_of(including)
    if low is None or high is None:
        return None
    if low > high:
        return (f"{FLOOR_NAMES[high]} (floor {high}) includes {FLOOR_NAMES[low]} "
                f"(floor {low}), a higher floor")
    owner = private_owner(included)
    if owner and not including.startswith(owner):
        if not (owner.startswith("core/") and including.startswith("tests/")):
            return f"a private header of {owner.rstrip('/')} (under {owner}src/)"
    plugin = plugin_of(including)
    if plugin and including.startswith(plugin + "include/"):
        if floor_of(included) >= 2 and not included.startswith(plugin):
            return (f"the public header of {plugin.rstrip('/')} exposes another plugin or "
                    "tool")
    return None


def main(argv):
    if len(argv) != 3:
        sys.exit(__doc__)
    repo = os.path.realpath(argv[1])
    tracked = set(subprocess.run(["git", "ls-files"], cwd=repo, check=True,
                                 capture_output=True, text=True).stdout.split("\n"))
    found = set()
    for source, entry in compile_db.by_source(compile_db.load(argv[2]), repo, tracked).items():
        resolver = include_graph.Resolver(
            include_graph.include_dirs(entry["command"], entry["directory"]), [repo])
        edges, _ = include_graph.unit_edges(os.path.join(repo, source), resolver)
        for including, included in edges:
            a, b = os.path.relpath(including, repo), os.path.relpath(included, repo)
            why = problem(a, b)
            if why:
                found.add(f"{a}: includes {b}: {why}")
    for line in sorted(found):
        print(line)
    sys.exit(1 if found else 0)


if __name__ == "__main__":
    main(sys.argv)
