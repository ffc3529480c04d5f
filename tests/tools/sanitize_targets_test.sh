#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# What tools/sanitize builds for the tests it is asked to run (tools/lib/test_targets.sh), read
# from this build tree's ctest list: tools/check's ASan selection names executables only (one
# test that needed "everything" would build swivel-lab, Ceres and the benchmarks under ASan on
# every check), a test that reads only the sources needs nothing built, and a test run through
# a script still means everything.
# Usage: sanitize_targets_test.sh REPO BUILD_DIR
set -euo pipefail
repo=$1
build=$2
# shellcheck source=../../tools/lib/test_targets.sh
source "$repo/tools/lib/test_targets.sh"
# shellcheck source=../../tools/lib/asan_selection.sh
source "$repo/tools/lib/asan_selection.sh"

failures=0
fail() { echo "FAIL: $*" >&2; failures=$(( failures + 1 )); }

selected=$(targets_of "$build" -L "$asan_labels" -E "$asan_skip")
count=$(grep -c . <<<"$selected" || true)
echo "tools/check's ASan selection: $count targets"
grep -qx all <<<"$selected" && fail "tools/check's ASan selection builds everything"
for needed in rt_control_loop_test config_test swivel-test-swpc-kinematics; do
  grep -qx "$needed" <<<"$selected" || fail "tools/check's ASan selection does not build $needed"
done

# Read whole first: grep -q leaves at its first match, and under pipefail a ctest still writing
# to the closed pipe would fail the check.
source_tests=$(ctest --test-dir "$build" -N -L '^source$')
grep -q 'Test *#' <<<"$source_tests" || fail "no test is labelled source"
[[ -z $(targets_of "$build" -L '^source$') ]] || fail "the source checks ask for a build"

[[ $(targets_of "$build" -R '^swiveld_unit_verify$') == all ]] ||
  fail "a test run through a script does not build everything"

[[ $failures -eq 0 ]] && echo "sanitize_targets_test: passed"
exit "$failures"
