# SPDX-License-Identifier: Apache-2.0
# shellcheck shell=bash
# Sourced by tools/check (and the test of what it builds for them).
# shellcheck disable=SC2034  # read by the scripts that source this
#
# The tests run under ASan+UBSan in tools/check: the libraries' unit tests, the real-time runtime,
# configuration, loader, fault table, run log and fuzz-corpus replays; not the unit tests of
# swivel-lab and the model-gap tool, which would build all of swivel-lab (Ceres included).
# Left to tools/sanitize: those, and the DDS, integration, security, service, soak, lab and
# calibration tests (they build the whole tree and run for many minutes under ASan).
asan_labels='^(unit|rt|config|loader|faults|fuzz)$'
# cli_executables_test too: it runs every executable's --version and usage errors, so under
# ASan it would build the whole tree (swivel-lab, the model-gap tool, the benchmarks) for
# argument parsing the main suite already checks. And the two validation generators' tests
# (tests/second_robot, tests/independent_robot): test code that ships nothing, whose simulations
# ran for 94 and 36 of the stage's 105 s; the project readers they read their files back with
# have unit tests and fuzzers of their own under ASan.
asan_skip='^(swivel-test-(lab|model-gap|second-robot|independent-robot)|cli_executables_test)'
