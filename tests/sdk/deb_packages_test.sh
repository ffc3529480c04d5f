#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Usage: deb_packages_test.sh BUILD_DIR CPACK
# Builds the two Debian packages from this build, checks what each holds and declares, then
# unpacks swivel into an empty root and runs the daemon from there, with the configuration,
# plugins and DDS file the package installed. Installing it with apt on a clean Debian 12 and
# starting it as its unit does is tools/deb-clean-install (root and the network: not a test).
set -euo pipefail
build=$1 cpack=$2
work=$(mktemp -d)
pid=""
cleanup() {
  if [[ -n $pid ]] && kill -0 "$pid" 2>/dev/null; then kill -KILL "$pid"; fi
  rm -rf "$work"
}
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

"$cpack" -G DEB -B "$work/out" --config "$build/CPackConfig.cmake" >"$work/cpack.log" 2>&1 ||
  { cat "$work/cpack.log"; fail "cpack"; }
runtime=$(ls "$work"/out/swivel_*.deb)
dev=$(ls "$work"/out/swivel-dev_*.deb)
echo "ok: built $(basename "$runtime") and $(basename "$dev")"

contents() { dpkg-deb -c "$1" | awk '{print $6}' | sed 's|^\./|/|'; }
contents "$runtime" >"$work/runtime.txt"
contents "$dev" >"$work/dev.txt"
prefix=$(grep -E '/bin/swiveld$' "$work/runtime.txt" | sed 's|/bin/swiveld$||')
[[ -n $prefix ]] || fail "swivel has no swiveld"
for f in /bin/swivelctl /lib/systemd/system/swiveld.service /lib/sysusers.d/swivel.conf \
         /lib/udev/rules.d/60-swivel-cpu-dma-latency.rules; do
  grep -qx "$prefix$f" "$work/runtime.txt" || fail "swivel lacks $prefix$f"
done
grep -q '/swivel/plugins/swivel_localization_raw_eg.so$' "$work/runtime.txt" ||
  fail "swivel lacks the plugins"
grep -q '/etc/swivel/swiveld.yaml$' "$work/runtime.txt" || fail "swivel lacks swiveld.yaml"
grep -q '/include/' "$work/runtime.txt" && fail "swivel carries headers (they are swivel-dev's)"
grep -q '/include/swivel/plugin/localization.hpp$' "$work/dev.txt" || fail "swivel-dev lacks headers"
grep -q '/cmake/Swivel/SwivelConfig.cmake$' "$work/dev.txt" || fail "swivel-dev lacks the package"
grep -q '/bin/' "$work/dev.txt" && fail "swivel-dev carries executables"
echo "ok: swivel holds the daemon, tools, plugins, unit, sysusers, udev rule and configuration;"
echo "    swivel-dev the headers and the CMake package"

depends=$(dpkg-deb -f "$runtime" Depends)
for d in libyaml-cpp0.7 libddsc0debian libspdlog1.10; do
  grep -q "$d" <<<"$depends" || fail "swivel does not depend on $d ($depends)"
done
# Every library an executable or plugin links directly comes from a declared package (or
# the C/C++ runtime every Debian has); what those need, their own packages declare.
dpkg-deb -x "$runtime" "$work/root"
missing=""
for f in $(find "$work/root" -type f \( -perm -u+x -o -name '*.so' \)); do
  readelf -h "$f" >/dev/null 2>&1 || continue
  for lib in $(readelf -d "$f" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
    # BLAS and LAPACK are alternatives: the package must name the virtual library.
    case "$lib" in
      libblas.so.3|liblapack.so.3)
        grep -qF "$lib" <<<"$depends" || missing+=" $lib($(basename "$f"))"
        continue ;;
    esac
    path=$(ldconfig -p | awk -v l="$lib" '$1 == l {print $NF; exit}') || true  # awk leaves early
    [[ -n $path ]] || continue
    pkg=$(dpkg -S "$(readlink -f "$path")" 2>/dev/null | head -n 1 | cut -d: -f1) || true
    case "$pkg" in
      ""|libc6|libstdc++6|libgcc-s1) ;;
      *) grep -qw -- "$pkg" <<<"$depends" || missing+=" $pkg($(basename "$f"))" ;;
    esac
  done
done
[[ -z $missing ]] || fail "linked directly but not declared:$missing"
conffiles=$(dpkg-deb --ctrl-tarfile "$runtime" | tar -xOf - ./conffiles)
grep -q '/etc/swivel/swiveld.yaml$' <<<"$conffiles" || fail "swiveld.yaml is not a conffile"
echo "ok: dependencies declared ($depends); configuration files are conffiles"

# The unpacked layout runs: the daemon finds its plugins next to itself and the
# configuration's relative files, and the installed configuration drives nothing.
config=$(find "$work/root" -path '*/etc/swivel/swiveld.yaml')
sed -i 's/^  realtime: true /  realtime: false /' "$config"
unset SWIVEL_PLUGIN_PATH
"$work/root$prefix/bin/swiveld" --config "$config" --check >"$work/check.log" 2>&1 ||
  { cat "$work/check.log"; fail "the packaged swiveld refuses the packaged configuration"; }
"$work/root$prefix/bin/swiveld" --config "$config" --no-dds >"$work/run.log" 2>&1 &
pid=$!
sleep 2
kill -0 "$pid" 2>/dev/null || { cat "$work/run.log"; fail "the packaged swiveld exited"; }
kill -TERM "$pid"
wait "$pid" || { cat "$work/run.log"; fail "the packaged swiveld did not stop cleanly"; }
pid=""
grep -q "loop running at 1000 Hz" "$work/run.log" || { cat "$work/run.log"; fail "no loop"; }
if grep -q "command source: script" "$work/run.log" || ! grep -q "mode idle" "$work/run.log"; then
  cat "$work/run.log"; fail "the packaged configuration drives the robot"
fi
echo "ok: the unpacked package's swiveld checks and runs its configuration, and stays idle"
