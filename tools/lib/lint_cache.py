# SPDX-License-Identifier: Apache-2.0
"""The record of what clang-tidy found in each source, keyed by everything that decides it.

A source's key is a SHA-256 over the clang-tidy version, every .clang-tidy of the
repository, the source's compile command (with the checkout's and the build tree's paths
replaced, so that another clone gets the same key), and the path and content of every
project file the source includes, directly or not (generated headers of the build tree
too). Edit any of them and the key changes, so the source is linted again. The record has a
line "PATH KEY RESULT" per source and key (the last few keys of a source are kept, so that
the record holds the committed content and another one being worked on), RESULT one of
  clean       this exact input was linted clean (no finding but those listed in
              tools/lint-known-findings.txt)
  findings    this exact input had findings when the record began: known, listed by every
              lint run, to be fixed
  unlinted    this exact input was not linted when the record began: listed by every lint
              run until a clean result replaces it
A result holds only for its key: a source whose key changed is linted, whatever it was.
Lint runs record only clean results, so the known ones can only go: a source edited (or
one of its headers) must be clean.

    lint_cache.py stale REPO BUILD LINT_DB RECORD VERSION
        prints the compiled sources whose key has no result in RECORD
    lint_cache.py known REPO BUILD LINT_DB RECORD VERSION
        prints "PATH RESULT" for the sources whose key has a result other than clean
    lint_cache.py unlinted REPO BUILD LINT_DB RECORD VERSION
        records every compiled source whose key has no result as unlinted (how the record
        began: the sources a first full run had not reached)
    lint_cache.py keys REPO BUILD LINT_DB VERSION PATH...
        prints "PATH KEY" for each source
    lint_cache.py record REPO BUILD LINT_DB RECORD VERSION KEYS RESULTS
        RESULTS has a line "PATH clean", "PATH findings" or "PATH failed" for each source
        linted: records each clean one whose key is still the one in the KEYS file (written
        by `keys` before linting, so a file edited while it was linted is not recorded);
        drops a clean result the source no longer has, and the lines of sources no longer
        tracked
"""

import fcntl
import hashlib
import os
import re
import shlex
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import compile_db  # noqa: E402
import include_graph  # noqa: E402

RECORD_HEADER = (
    "# What clang-tidy found in each source: path, the key of everything that decides it, and\n"
    "# the result (tools/lib/lint_cache.py). Written by tools/lint; commit it with the sources.\n"
)
RESULTS = ("clean", "findings", "unlinted")
KEYS_KEPT = 4  # per source


class Keys:
    def __init__(self, repo, build, lint_db, version, tracked=None):
        self.repo = os.path.realpath(repo)
        self.build = os.path.realpath(build)
        if tracked is None:
            tracked = subprocess.run(["git", "ls-files"], cwd=self.repo, check=True,
                                     capture_output=True, text=True).stdout.split("\n")
        self.tracked = set(tracked)
        self.sources = compile_db.by_source(compile_db.load(lint_db),
                                            self.repo, self.tracked)
        digest = hashlib.sha256(version.encode())
        for config in sorted(p for p in self.tracked if os.path.basename(p) == ".clang-tidy"):
            digest.update(config.encode() + b"\0" + self._read(os.path.join(self.repo, config)))
        self.common = digest.hexdigest()
        self.content = {}

    def _portable(self, text):
        # The build tree first: it may lie inside the checkout.
        return text.replace(self.build, "<build>").replace(self.repo, "<repo>")

    def _read(self, path):
        with open(path, "rb") as f:
            return f.read()

    def _generated_portable(self, text):
        # Generated files name the folders they were generated in, also as include guards
        # (idlc: /a/build/x.h -> DDSC__A_BUILD_X_H), and the version header carries the
        # checkout's `git describe` (another commit, or -dirty), which no finding depends on.
        text = self._portable(text)
        for folder, mark in ((self.build, "<BUILD>"), (self.repo, "<REPO>")):
            text = text.replace(re.sub(r"[^A-Za-z0-9]", "_", folder).upper(), mark)
        return re.sub(r'(kGitDescribe = )"[^"]*"', r'\1"<describe>"', text)

    def _content_hash(self, path):
        if path not in self.content:
            data = self._read(path)
            if path.startswith(os.path.join(self.build, "")):
                data = self._generated_portable(data.decode("utf-8", "replace")).encode()
            self.content[path] = hashlib.sha256(data).hexdigest()
        return self.content[path]

    def key(self, source):
        entry = self.sources.get(source)
        if entry is None or not os.path.isfile(os.path.join(self.repo, source)):
            return None
        words = shlex.split(entry["command"])
        if "-o" in words:
            i = words.index("-o")
            del words[i:i + 2]
        digest = hashlib.sha256(self.common.encode())
        digest.update(self._portable(" ".join(words)).encode())
        resolver = include_graph.Resolver(
            include_graph.include_dirs(entry["command"], entry["directory"]),
            [self.repo, self.build])
        _, files = include_graph.unit_edges(os.path.join(self.repo, source), resolver)
        for path in sorted(files):
            digest.update(b"\0" + self._portable(path).encode() + b" " +
                          self._content_hash(path).encode())
        return digest.hexdigest()


def read_record(path):
    """{source: {key: result}}, each source's keys oldest first."""
    record = {}
    if os.path.exists(path):
        with open(path, encoding="utf-8") as f:
            for number, line in enumerate(f, 1):
                if not line.strip() or line.startswith("#"):
                    continue
                fields = line.split()
                if len(fields) != 3 or fields[2] not in RESULTS:
                    sys.exit(f"{path}:{number}: expected PATH KEY RESULT, RESULT one of "
                             f"{', '.join(RESULTS)}; got: {line.strip()}")
                record.setdefault(fields[0], {})[fields[1]] = fields[2]
    return record


def result_of(record, source, key):
    return record.get(source, {}).get(key)


def write_record(path, record):
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(RECORD_HEADER)
        for source in sorted(record):
            for key, result in record[source].items():
                f.write(f"{source} {key} {result}\n")
    os.replace(tmp, path)


def main(argv):
    if len(argv) < 2:
        sys.exit(__doc__)
    command = argv[1]
    if command == "stale" and len(argv) == 7:
        repo, build, lint_db, record_path, version = argv[2:]
        keys = Keys(repo, build, lint_db, version)
        record = read_record(os.path.join(repo, record_path))
        for source in sorted(keys.sources):
            if result_of(record, source, keys.key(source)) is None:
                print(source)
    elif command == "known" and len(argv) == 7:
        repo, build, lint_db, record_path, version = argv[2:]
        keys = Keys(repo, build, lint_db, version)
        record = read_record(os.path.join(repo, record_path))
        for source in sorted(keys.sources):
            result = result_of(record, source, keys.key(source))
            if result not in (None, "clean"):
                print(source, result)
    elif command == "unlinted" and len(argv) == 7:
        repo, build, lint_db, record_path, version = argv[2:]
        keys = Keys(repo, build, lint_db, version)
        record_path = os.path.join(repo, record_path)
        record = read_record(record_path)
        for source in keys.sources:
            key = keys.key(source)
            if result_of(record, source, key) is None:
                record.setdefault(source, {})[key] = "unlinted"
        write_record(record_path, record)
    elif command == "keys" and len(argv) >= 6:
        repo, build, lint_db, version = argv[2:6]
        keys = Keys(repo, build, lint_db, version)
        for source in argv[6:]:
            print(source, keys.key(source) or "-")
    elif command == "record" and len(argv) == 9:
        repo, build, lint_db, record_path, version, keys_file, results_file = argv[2:9]
        keys = Keys(repo, build, lint_db, version)
        with open(keys_file, encoding="utf-8") as f:
            before = dict(line.split() for line in f if line.strip())
        with open(results_file, encoding="utf-8") as f:
            results = dict(line.split() for line in f if line.strip())
        record_path = os.path.join(repo, record_path)
        # Two lint runs at once each add their own sources.
        with open(os.path.join(os.path.dirname(lint_db), "record.lock"), "w",
                  encoding="utf-8") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            record = {s: k for s, k in read_record(record_path).items() if s in keys.tracked}
            for source, result in results.items():
                key = keys.key(source)
                entries = record.setdefault(source, {})
                if result == "clean" and key is not None and before.get(source) == key:
                    entries.pop(key, None)
                    entries[key] = result  # the newest last
                    for old in list(entries)[:-KEYS_KEPT]:
                        del entries[old]
                elif entries.get(key) == "clean":
                    del entries[key]
                if not entries:
                    del record[source]
            write_record(record_path, record)
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main(sys.argv)
