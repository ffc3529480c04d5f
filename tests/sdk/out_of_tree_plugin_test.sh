#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Usage: out_of_tree_plugin_test.sh BUILD_DIR SOURCE_DIR SWIVELD CMAKE
set -euo pipefail
build=$1 source=$2 swiveld=$3 cmake=$4
work=$(mktemp -d)
daemon_pid=""
cleanup() {
  if [[ -n $daemon_pid ]] && kill -0 "$daemon_pid" 2>/dev/null; then kill -KILL "$daemon_pid"; fi
  rm -rf "$work"
}
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# 1. Install only the SDK, as a package would, into a staging root.
DESTDIR=$work/stage "$cmake" --install "$build" --component dev >"$work/install.log" ||
  { cat "$work/install.log"; fail "installing the dev component"; }
prefix=$(find "$work/stage" -name SwivelConfig.cmake -printf '%h\n' | head -n 1)
[[ -n $prefix ]] || fail "no SwivelConfig.cmake was installed"
prefix=${prefix%/lib*/cmake/Swivel}
for f in include/swivel/plugin/localization.hpp include/swivel/plugin/abi.hpp \
         include/swivel/testing/alloc_guard.hpp share/swivel/idl/swivel.idl; do
  [[ -f $prefix/$f ]] || fail "the SDK lacks $f"
done
# Nothing but the SDK: no daemon, no plugins, no configuration.
if [[ -n $(find "$work/stage" -name swiveld -o -name 'swivel_localization_*.so') ]]; then
  fail "the dev component installs more than the SDK"
fi
echo "ok: SDK installed under $prefix"

# 2. The example, configured with nothing but the staged prefix.
"$cmake" -S "$source/examples/out_of_tree_plugin" -B "$work/example" \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release >"$work/configure.log" 2>&1 ||
  { cat "$work/configure.log"; fail "configuring the example against the SDK"; }
"$cmake" --build "$work/example" >"$work/build.log" 2>&1 ||
  { cat "$work/build.log"; fail "building the example"; }
plugin=$work/example/swivel_localization_wheel_odometry.so
[[ -f $plugin ]] || fail "the example did not produce $plugin"
exported=$(nm -D --defined-only "$plugin" | awk '$2 == "T" {print $3}' | grep -v '^_' || true)
[[ $exported == swivel_plugin_descriptor ]] ||
  fail "the plugin exports more than its entry point: $exported"
echo "ok: built $plugin, exporting only swivel_plugin_descriptor"
ctest --test-dir "$work/example" --output-on-failure >"$work/ctest.log" 2>&1 ||
  { cat "$work/ctest.log"; fail "the example's own test under the allocation guard"; }
echo "ok: the example's real-time methods allocate nothing (Swivel::alloc_guard)"

# 3. The daemon checks and runs a configuration that uses it.
mkdir -p "$work/etc"
cp -r "$source/config/robots" "$source/config/dds" "$work/etc/"
sed -e 's/^  plugin: raw_eg$/  plugin: wheel_odometry/' \
    -e 's/^    heading_source: gyro .*$/    distance_scale: 1.0/' \
    -e 's/^  realtime: true /  realtime: false /' \
    "$source/config/swiveld.yaml" >"$work/etc/swiveld.yaml"
grep -q 'plugin: wheel_odometry' "$work/etc/swiveld.yaml" || fail "could not select the plugin"
export SWIVEL_PLUGIN_PATH="$work/example:${SWIVEL_PLUGIN_BUILD_DIR:?}"
"$swiveld" --config "$work/etc/swiveld.yaml" --check >"$work/check.log" 2>&1 ||
  { cat "$work/check.log"; fail "swiveld --check refused the configuration"; }
echo "ok: swiveld --check accepts it"
"$swiveld" --config "$work/etc/swiveld.yaml" --no-dds >"$work/run.log" 2>&1 &
daemon_pid=$!
sleep 3
kill -0 "$daemon_pid" 2>/dev/null || { cat "$work/run.log"; fail "swiveld exited early"; }
kill -TERM "$daemon_pid"
wait "$daemon_pid" || { cat "$work/run.log"; fail "swiveld did not stop cleanly"; }
daemon_pid=""
grep -q "wheel_odometry" "$work/run.log" || { cat "$work/run.log"; fail "the log never names wheel_odometry"; }
# The status line's pose: the script drives the square, so the robot has moved.
grep -q 'localization wheel_odometry' "$work/run.log" ||
  { cat "$work/run.log"; fail "the loop did not run the plugin"; }
moved=$(grep -Eo 'pose x=[-]?[0-9]+\.[0-9]+' "$work/run.log" | tail -n 1 | cut -d= -f2)
[[ -n $moved ]] || { cat "$work/run.log"; fail "no status line"; }
awk -v x="$moved" 'BEGIN { exit !(x > 0.3 || x < -0.3) }' ||
  { tail -n 5 "$work/run.log"; fail "the estimate did not move (x=$moved)"; }
echo "ok: swiveld ran the out-of-tree plugin for 3 s (x=$moved m) and stopped cleanly"
