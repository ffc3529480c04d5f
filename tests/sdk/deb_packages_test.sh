#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Usage: deb_packages_test.sh BUILD_DIR CPACK
# Builds the two Debian packages from this build, checks what each holds and declares, then
# unpacks swivel into an empty root and runs the daemon from there, with the configuration,
# plugins and DDS file the package installed. Installing it with apt on a clean Debian 12 and
# starting it as its unit does is tools/deb-clean-install (root and the network); under
# systemd as PID 1, ctest swiveld_systemd_install (label systemd_boot).
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

# The package is laid out for /usr whatever prefix this build was configured with: the unit
# starts the packaged swiveld, with the packaged configuration, and the conffiles are
# exactly the files in /etc.
dpkg-deb -x "$runtime" "$work/root"
unit="$work/root/usr/lib/systemd/system/swiveld.service"
[[ -f $unit ]] || fail "swivel has no /usr/lib/systemd/system/swiveld.service"
exec_start=$(sed -n 's/^ExecStart=//p' "$unit")
read -r exe _ config_file _ <<<"$exec_start"
[[ $exe == /usr/bin/swiveld && -x $work/root$exe ]] ||
  fail "the unit's ExecStart= runs $exe, not the packaged /usr/bin/swiveld ($exec_start)"
[[ $config_file == /etc/swivel/swiveld.yaml && -f $work/root$config_file ]] ||
  fail "the unit's ExecStart= reads $config_file, not the packaged /etc/swivel/swiveld.yaml"
dds_uri=$(sed -n 's/^Environment=CYCLONEDDS_URI=//p' "$unit")
[[ $dds_uri == file:///etc/swivel/dds/cyclonedds.xml && -f $work/root${dds_uri#file://} ]] ||
  fail "the unit's CYCLONEDDS_URI=$dds_uri is not a packaged file"
grep -q '/usr/local' "$unit" && fail "the packaged unit names /usr/local"
conffiles=$(dpkg-deb --ctrl-tarfile "$runtime" | tar -xOf - ./conffiles | sort)
etc_files=$(cd "$work/root" && find etc -type f | sed 's|^|/|' | sort)
[[ $conffiles == "$etc_files" ]] ||
  fail "conffiles and the files in /etc differ: $(diff <(echo "$conffiles") <(echo "$etc_files") | grep '^[<>]' | tr '\n' ' ')"
grep -q /usr/local "$work/runtime.txt" "$work/dev.txt" && fail "a package installs into /usr/local"
# systemd-analyze verify on the unit as packaged: its ExecStart= must exist and run.
if command -v systemd-analyze >/dev/null; then
  sed "s|^ExecStart=/usr/bin/swiveld|ExecStart=$work/root/usr/bin/swiveld|" "$unit" \
    >"$work/swiveld.service"
  out=$(systemd-analyze verify --man=no "$work/swiveld.service" 2>&1) ||
    fail "systemd-analyze verify on the packaged unit: $out"
  [[ -z $out ]] || fail "systemd-analyze verify on the packaged unit: $out"
  echo "ok: systemd-analyze verify on the packaged unit (ExecStart= the unpacked swiveld): clean"
fi
echo "ok: the unit runs /usr/bin/swiveld --config /etc/swivel/swiveld.yaml with $dds_uri, all in the package; conffiles are exactly /etc"

# Debian's metadata: a maintainer, a description, the documentation files.
for deb in "$runtime" "$dev"; do
  name=$(dpkg-deb -f "$deb" Package)
  maintainer=$(dpkg-deb -f "$deb" Maintainer)
  [[ $maintainer =~ ^[^\<]+\ \<[^@\>]+@[^\>]+\>$ && $maintainer != *localhost* ]] ||
    fail "$name: Maintainer '$maintainer' is no name and address"
  [[ $(dpkg-deb -f "$deb" Description | wc -l) -ge 3 ]] || fail "$name has no extended description"
  contents "$deb" >"$work/list"
  for f in copyright changelog.gz; do
    grep -qx "/usr/share/doc/$name/$f" "$work/list" || fail "$name lacks /usr/share/doc/$name/$f"
  done
done
echo "ok: both packages have a maintainer, an extended description, copyright and changelog"

# The maintainer scripts, run with every command they call replaced by one that records its
# arguments: nothing happens without systemd as PID 1, and with it, removal stops the
# service and an upgrade restarts it (never a fresh install: the administrator enables it).
for script in postinst prerm postrm; do
  dpkg-deb --ctrl-tarfile "$runtime" | tar -xOf - "./$script" >"$work/$script" ||
    fail "swivel has no $script"
  chmod +x "$work/$script"
  sh -n "$work/$script" || fail "$script is not valid sh"
done
mkdir -p "$work/stubs"
for cmd in systemctl deb-systemd-invoke deb-systemd-helper systemd-sysusers udevadm rm; do
  printf '#!/bin/sh\necho "%s $*" >>"$CALLS"\n' "$cmd" >"$work/stubs/$cmd"
  chmod +x "$work/stubs/$cmd"
done
# calls SYSTEMD(yes|no) SCRIPT ARGS...: the commands SCRIPT ran, one line each.
calls() {
  local systemd=$1
  shift
  : >"$work/calls"
  if [[ $systemd == yes ]]; then
    # A private mount namespace with /run/systemd/system, as systemd as PID 1 makes it.
    unshare --mount --propagation private sh -c \
      'stubs=$0 calls=$1; shift; mount -t tmpfs tmpfs /run && mkdir -p /run/systemd/system &&
       exec env -i PATH="$stubs" CALLS="$calls" "$@"' \
      "$work/stubs" "$work/calls" "$work/$1" "${@:2}" || fail "$* failed (systemd running)"
  else
    env -i PATH="$work/stubs" CALLS="$work/calls" "$work/$1" "${@:2}" || fail "$* failed"
  fi
  tr '\n' ';' <"$work/calls"
}
expect_calls() {
  local want=$1 got
  shift
  got=$(calls "$@")
  [[ $got == "$want" ]] || fail "$*: ran '$got', expected '$want'"
}
sysusers='systemd-sysusers swivel.conf;udevadm trigger --subsystem-match=misc --sysname-match=cpu_dma_latency;deb-systemd-helper update-state swiveld.service;'
if [[ ! -d /run/systemd/system ]]; then
  expect_calls "$sysusers" no postinst configure
  expect_calls "$sysusers" no postinst configure 0.0.9
  expect_calls "" no prerm remove
  expect_calls "" no postrm remove
  # deb-systemd-helper keeps its state in files: purging it needs no systemd.
  expect_calls "deb-systemd-helper purge swiveld.service;deb-systemd-helper unmask swiveld.service;rm -rf /var/lib/swivel /var/log/swivel;" \
    no postrm purge
  echo "ok: without systemd the scripts create the user and start, stop or restart nothing"
fi
if [[ $(id -u) -eq 0 ]]; then
  expect_calls "${sysusers}systemctl --system daemon-reload;" yes postinst configure
  expect_calls "${sysusers}systemctl --system daemon-reload;deb-systemd-invoke try-restart swiveld.service;" \
    yes postinst configure 0.0.9
  expect_calls "deb-systemd-invoke stop swiveld.service;" yes prerm remove
  expect_calls "" yes prerm upgrade 0.1.1
  expect_calls "systemctl --system daemon-reload;" yes postrm remove
  expect_calls "deb-systemd-helper purge swiveld.service;deb-systemd-helper unmask swiveld.service;rm -rf /var/lib/swivel /var/log/swivel;" \
    yes postrm purge
  echo "ok: with systemd, removal stops the service, an upgrade restarts it if it runs, purge forgets it"
else
  echo "note: not root: the maintainer scripts were not run as with systemd as PID 1"
fi

# lintian: no error and no warning that is not overridden (with its reason) in the package.
if command -v lintian >/dev/null; then
  lintian --allow-root "$runtime" "$dev" >"$work/lintian.log" 2>&1 || true
  if grep -E '^(E|W):' "$work/lintian.log"; then
    fail "lintian reports the errors and warnings above"
  fi
  echo "ok: lintian: no errors or warnings"
else
  echo "note: lintian is not installed (tools/setup installs it): not run"
fi

depends=$(dpkg-deb -f "$runtime" Depends)
for d in libyaml-cpp0.7 libddsc0debian libspdlog1.10 libc6 libstdc++6; do
  grep -q "$d" <<<"$depends" || fail "swivel does not depend on $d ($depends)"
done
grep -q 'libceres' <<<"$depends" && fail "swivel depends on Ceres, which is linked statically"
grep -qE 'libc6 \(>= [0-9.]+\)' <<<"$depends" || fail "the libc6 dependency has no version: $depends"
# Every library an executable or plugin links directly comes from a declared package;
# what those need, their own packages declare.
missing=""
linked_pkgs=" "  # the packages whose libraries something in swivel links directly
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
    # dpkg knows a file by the path its package ships (with merged /usr, /lib or /usr/lib).
    pkg=""
    for candidate in "$path" "$(readlink -f "$path")"; do
      for p in "$candidate" "/usr${candidate#/usr}" "${candidate#/usr}"; do
        pkg=$(dpkg -S "$p" 2>/dev/null | head -n 1 | cut -d: -f1) || true
        [[ -z $pkg ]] || break 2
      done
    done
    case "$pkg" in
      "") ;;
      *) linked_pkgs+="$pkg "
         grep -qw -- "$pkg" <<<"$depends" || missing+=" $pkg($(basename "$f"))" ;;
    esac
  done
done
[[ -z $missing ]] || fail "linked directly but not declared:$missing"
# And the other way: a library package is declared only when something links it directly
# (a statically linked library, like Ceres, must not appear). Alternatives (BLAS, LAPACK)
# resolve to whichever provider this host has: not checked here.
unlinked=""
# A shlibs file may name a transition's package (libspdlog1.10-fmt9 for libspdlog1.10).
for dep in $(tr ',' '\n' <<<"$depends" | grep -v '|' | awk '{print $1}' | grep '^lib'); do
  found=0
  for pkg in $linked_pkgs; do
    [[ $dep == "$pkg" || $dep == "$pkg"-* ]] && { found=1; break; }
  done
  [[ $found == 1 ]] || unlinked+=" $dep"
done
[[ -z $unlinked ]] || fail "declared but linked by nothing in swivel:$unlinked"
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
