#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Imports every run of one OptiOdom session directory (data/diff/<kind>/<session>/ of the
# repository sousarbarb/optiodom: <session>_run-NN.csv) into OUT_DIR/<session>_run-NN.csv with
# config/import/optiodom_diff.yaml, checked against config/robots/optiodom_diff.yaml.
#   tools/lab/import_optiodom.sh SESSION_DIR OUT_DIR [SWIVEL_LAB]
# SWIVEL_LAB defaults to build/bin/swivel-lab. Stops at the first run that does not import.
set -euo pipefail

if [[ $# -lt 2 || $# -gt 3 ]]; then
  echo "usage: $0 SESSION_DIR OUT_DIR [SWIVEL_LAB]" >&2
  exit 2
fi
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
session_dir=$1
out_dir=$2
lab=${3:-$repo/build/bin/swivel-lab}
[[ -d $session_dir ]] || { echo "$0: no directory $session_dir" >&2; exit 1; }
[[ -x $lab ]] || { echo "$0: $lab is not executable (build swivel-lab first)" >&2; exit 1; }

shopt -s nullglob
runs=("$session_dir"/*_run-[0-9][0-9].csv)
if [[ ${#runs[@]} -eq 0 ]]; then
  echo "$0: no <session>_run-NN.csv in $session_dir" >&2
  exit 1
fi
mkdir -p "$out_dir"
for run in "${runs[@]}"; do
  "$lab" import --map "$repo/config/import/optiodom_diff.yaml" \
    --model "$repo/config/robots/optiodom_diff.yaml" \
    --out "$out_dir/$(basename "$run")" "$run"
done
