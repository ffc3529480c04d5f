#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Usage: minimal_configure_test.sh SOURCE_DIR CMAKE
# Configures Swivel as if GoogleTest, Google Benchmark and Ceres were not installed.
set -euo pipefail
source=$1 cmake=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
"$cmake" -S "$source" -B "$work" -DCMAKE_DISABLE_FIND_PACKAGE_GTest=ON \
  -DCMAKE_DISABLE_FIND_PACKAGE_benchmark=ON -DCMAKE_DISABLE_FIND_PACKAGE_Ceres=ON \
  >"$work.log" 2>&1 || { cat "$work.log"; rm -f "$work.log"; fail "configuring without them"; }
grep -q "GTEST not found" "$work.log" || fail "GoogleTest was found anyway"
rm -f "$work.log"
targets=$("$cmake" --build "$work" --target help)
for t in swiveld swivelctl swivel_hardware_sim swivel_drivetrain_differential \
         swivel_drivetrain_swpc swivel_localization_raw_eg swivel_localization_kalman \
         swivel_localization_lsm swivel_calibration_swpc_geometric; do
  grep -q "\.\.\. $t\$" <<<"$targets" || fail "no target $t without the test frameworks"
done
echo "ok: swiveld, swivelctl and every plugin configure without GoogleTest, benchmark, Ceres"
