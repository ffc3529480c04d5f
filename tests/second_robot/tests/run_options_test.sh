#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# swivel-second-run's options with --case: --no-noise and --true change the case (and say so),
# an option the case fixes itself (--rate, --robot, ...) is a usage error, not ignored,
# --hidden-out writes the generator's state row for row, and a caster run says how hard its
# steering servos press against their tyres.
# Usage: run_options_test.sh SWIVEL_SECOND_RUN
set -euo pipefail
tool=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

failures=0
fail() { echo "FAIL: $*" >&2; failures=$(( failures + 1 )); }

case_args=(--case clean --index 3 --seeds smoke)
"$tool" "${case_args[@]}" --out "$work/noisy.csv" >"$work/noisy.txt"
"$tool" "${case_args[@]}" --no-noise --out "$work/quiet.csv" >"$work/quiet.txt"
cmp -s "$work/noisy.csv" "$work/quiet.csv" && fail "--no-noise left the case's run as it was"
grep -q '(changed: no noise)' "$work/quiet.txt" || fail "--no-noise is not in the description"

for option in "--rate 30" "--robot trike3" "--script circles" "--duration 20" "--seed 5" \
              --no-accel-limits-in-model --no-steering-limit-in-model --fractional-counts; do
  rc=0
  # shellcheck disable=SC2086  # the option and its value are two words
  "$tool" "${case_args[@]}" $option --out "$work/x.csv" >/dev/null 2>"$work/err.txt" || rc=$?
  [[ $rc -eq 2 ]] || fail "$option with --case: exit $rc, expected 2 (usage error)"
  grep -q -- '--case' "$work/err.txt" || fail "$option with --case: the error does not name --case"
done

# --hidden-out writes the generator's own state beside the log, one line per row.
"$tool" "${case_args[@]}" --out "$work/run.csv" --hidden-out "$work/hidden.csv" >"$work/h.txt"
grep -q '^t,x,y,yaw,vx,vy,wz,' "$work/hidden.csv" || fail "--hidden-out: no header of the state"
rows=$(grep -vc '^#' "$work/run.csv")
hidden=$(grep -vc '^#' "$work/hidden.csv")
[[ $rows -eq $hidden ]] || fail "--hidden-out: $hidden lines against the log's $rows"
grep -q "wrote $work/hidden.csv" "$work/h.txt" || fail "--hidden-out: not reported"

# A caster robot's run says how hard its steering servos press against their tyres; a
# differential robot's (smoke clean index 3: mini_diff) says nothing of servos.
"$tool" --case clean --index 0 --seeds smoke --out "$work/x.csv" >"$work/caster.txt"
grep -Eq '^steering servos while driving: largest median error [0-9.]+ mrad \(not fighting their tyres\)$' \
  "$work/caster.txt" || fail "a clean caster run: no line on its steering servos"
grep -q 'steering servos' "$work/noisy.txt" && fail "a differential run speaks of steering servos"

rc=0
"$tool" --index 3 --out "$work/x.csv" >/dev/null 2>&1 || rc=$?
[[ $rc -eq 2 ]] || fail "--index without --case: exit $rc, expected 2"

[[ $failures -eq 0 ]] && echo "run_options_test: passed"
exit "$failures"
