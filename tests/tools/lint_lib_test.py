# SPDX-License-Identifier: Apache-2.0
"""tools/lint's cache keys and include check on a small made-up tree."""

import json
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../tools/lib"))
import include_layers  # noqa: E402
import lint_cache  # noqa: E402


def write(root, path, text):
    full = os.path.join(root, path)
    os.makedirs(os.path.dirname(full), exist_ok=True)
    with open(full, "w", encoding="utf-8") as f:
        f.write(text)


class MadeUpTree(unittest.TestCase):
    """A git repository with a plugin source including a core header, and its database."""

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.repo = os.path.realpath(self.tmp.name)
        self.build = os.path.join(self.repo, "build")
        write(self.repo, "core/include/swivel/types.hpp", "#pragma once\nstruct A {};\n")
        write(self.repo, "core/include/swivel/unused.hpp", "#pragma once\n")
        write(self.repo, "plugins/k/n/src/p.cpp",
              '#include "swivel/types.hpp"\n#include <vector>\n')
        write(self.repo, ".clang-tidy", "Checks: '-*'\n")
        subprocess.run(["git", "init", "-q"], cwd=self.repo, check=True)
        subprocess.run(["git", "add", "."], cwd=self.repo, check=True)
        os.makedirs(os.path.join(self.build, "lint"))
        self.db = os.path.join(self.build, "lint", "compile_commands.json")
        self.write_db(["-I" + os.path.join(self.repo, "core/include")])

    def tearDown(self):
        self.tmp.cleanup()

    def write_db(self, flags):
        command = " ".join(["c++"] + flags + ["-o", "p.o", "-c",
                                              os.path.join(self.repo, "plugins/k/n/src/p.cpp")])
        with open(self.db, "w", encoding="utf-8") as f:
            json.dump([{"directory": self.build, "file": os.path.join(
                self.repo, "plugins/k/n/src/p.cpp"), "command": command}], f)

    def key(self, version="clang-tidy 14"):
        return lint_cache.Keys(self.repo, self.build, self.db, version).key("plugins/k/n/src/p.cpp")


class KeyTest(MadeUpTree):
    def test_same_inputs_same_key(self):
        self.assertEqual(self.key(), self.key())

    def test_an_included_header_changes_the_key(self):
        before = self.key()
        write(self.repo, "core/include/swivel/types.hpp", "#pragma once\nstruct B {};\n")
        self.assertNotEqual(before, self.key())

    def test_a_header_not_included_leaves_the_key(self):
        before = self.key()
        write(self.repo, "core/include/swivel/unused.hpp", "#pragma once\nstruct C {};\n")
        self.assertEqual(before, self.key())

    def test_flags_configuration_and_version_change_the_key(self):
        before = self.key()
        self.assertNotEqual(before, self.key(version="clang-tidy 15"))
        write(self.repo, ".clang-tidy", "Checks: 'bugprone-*'\n")
        self.assertNotEqual(before, self.key())
        write(self.repo, ".clang-tidy", "Checks: '-*'\n")
        self.write_db(["-I" + os.path.join(self.repo, "core/include"), "-O0"])
        self.assertNotEqual(before, self.key())

    def test_another_checkout_gets_the_same_key(self):
        other = MadeUpTree()
        other.setUp()
        try:
            self.assertNotEqual(self.repo, other.repo)
            self.assertEqual(self.key(), other.key())
        finally:
            other.tearDown()

    def test_the_output_file_does_not_change_the_key(self):
        before = self.key()
        with open(self.db, encoding="utf-8") as f:
            db = json.load(f)
        db[0]["command"] = db[0]["command"].replace("-o p.o", "-o q.o")
        with open(self.db, "w", encoding="utf-8") as f:
            json.dump(db, f)
        self.assertEqual(before, self.key())

    def test_record_round_trip_and_bad_line(self):
        path = os.path.join(self.repo, "record.txt")
        record = {"a.cpp": {"k1": "clean", "k0": "unlinted"}, "b.cpp": {"k2": "findings"}}
        lint_cache.write_record(path, record)
        self.assertEqual(lint_cache.read_record(path), record)
        self.assertEqual(list(lint_cache.read_record(path)["a.cpp"]), ["k1", "k0"])
        write(self.repo, "record.txt", "a.cpp k1 fine\n")
        with self.assertRaises(SystemExit) as raised:
            lint_cache.read_record(path)
        self.assertIn("record.txt:1: expected PATH KEY RESULT", str(raised.exception))


class RecordTest(MadeUpTree):
    def record(self, result, before_key=None):
        keys_file = os.path.join(self.repo, "keys.txt")
        results_file = os.path.join(self.repo, "results.txt")
        write(self.repo, "keys.txt", f"plugins/k/n/src/p.cpp {before_key or self.key()}\n")
        write(self.repo, "results.txt", f"plugins/k/n/src/p.cpp {result}\n")
        lint_cache.main(["lint_cache.py", "record", self.repo, self.build, self.db,
                         "record.txt", "clang-tidy 14", keys_file, results_file])
        return lint_cache.read_record(os.path.join(self.repo, "record.txt"))

    def test_only_a_clean_result_is_recorded(self):
        self.assertEqual(self.record("clean"), {"plugins/k/n/src/p.cpp": {self.key(): "clean"}})
        self.assertEqual(self.record("findings"), {})
        self.assertEqual(self.record("failed"), {})

    def test_a_source_keeps_its_last_keys(self):
        lint_cache.write_record(os.path.join(self.repo, "record.txt"), {
            "plugins/k/n/src/p.cpp": {f"old{i}": "clean" for i in range(5)}})
        entries = self.record("clean")["plugins/k/n/src/p.cpp"]
        self.assertEqual(list(entries), ["old2", "old3", "old4", self.key()])

    def test_a_source_edited_while_it_was_linted_is_not_recorded(self):
        self.assertEqual(self.record("clean", before_key="0" * 64), {})

    def test_a_known_result_stays_until_the_source_is_clean(self):
        lint_cache.write_record(os.path.join(self.repo, "record.txt"),
                                {"plugins/k/n/src/p.cpp": {self.key(): "findings"}})
        self.assertEqual(self.record("findings"),
                         {"plugins/k/n/src/p.cpp": {self.key(): "findings"}})
        self.assertEqual(self.record("clean"),
                         {"plugins/k/n/src/p.cpp": {self.key(): "clean"}})


class LayersTest(unittest.TestCase):
    def test_down_and_across_are_allowed(self):
        for including, included in [
                ("plugins/hardware/sim/src/w.cpp", "core/include/swivel/types.hpp"),
                ("plugins/hardware/sim/src/w.cpp",
                 "plugins/drivetrain/swpc/include/swivel/swpc/k.hpp"),
                ("tools/lab/x.cpp", "libs/stats/include/swivel/stats/summary.hpp"),
                ("tools/lab/x.cpp", "plugins/hardware/sim/include/swivel/sim/world.hpp"),
                ("tests/daemon/t.cpp", "core/src/daemon/calibration_runner.hpp"),
                ("plugins/k/n/tests/t.cpp", "tests/support/alloc_guard.hpp"),
                ("core/src/daemon/d.cpp", "core/src/daemon/plugin_set.hpp")]:
            self.assertIsNone(include_layers.problem(including, included), (including, included))

    def test_a_plugin_depending_on_a_tool_is_refused(self):
        why = include_layers.problem("plugins/calibration/g/tools/mc.cpp",
                                     "tools/stats/include/swivel/stats/summary.hpp")
        self.assertIn("includes tools (floor 3), a higher floor", why)

    def test_core_including_a_plugin_is_refused(self):
        self.assertIn("a higher floor", include_layers.problem(
            "core/src/daemon/d.cpp", "plugins/hardware/sim/include/swivel/sim/world.hpp"))

    def test_a_plugin_test_reading_the_daemon_private_headers_is_refused(self):
        why = include_layers.problem("plugins/calibration/g/tests/t.cpp",
                                     "core/src/daemon/calibration_runner.hpp")
        self.assertIn("a private header of core (under core/src/)", why)

    def test_a_plugin_public_header_exposing_another_plugin_is_refused(self):
        why = include_layers.problem("plugins/calibration/g/include/swivel/calibration/s.hpp",
                                     "plugins/hardware/sim/include/swivel/sim/world.hpp")
        self.assertIn("public header of plugins/calibration/g exposes another plugin", why)

    def test_the_check_runs_over_a_database(self):
        tree = MadeUpTree()
        tree.setUp()
        try:
            write(tree.repo, "core/include/swivel/types.hpp",
                  '#pragma once\n#include "../../../plugins/k/n/src/p.hpp"\n')
            write(tree.repo, "plugins/k/n/src/p.hpp", "#pragma once\n")
            subprocess.run(["git", "add", "."], cwd=tree.repo, check=True)
            run = subprocess.run([sys.executable, include_layers.__file__, tree.repo, tree.db],
                                 capture_output=True, text=True, check=False)
            self.assertEqual(run.returncode, 1, run.stderr)
            self.assertIn("core/include/swivel/types.hpp: includes plugins/k/n/src/p.hpp: "
                          "core (floor 0) includes plugins (floor 2), a higher floor", run.stdout)
        finally:
            tree.tearDown()


if __name__ == "__main__":
    unittest.main()
