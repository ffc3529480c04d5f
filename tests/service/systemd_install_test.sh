#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Usage: systemd_install_test.sh BUILD_DIR CPACK SOURCE_DIR [DXL_EMULATOR]
# The Debian package of this build under systemd as PID 1: tools/deb-clean-install --systemd
# on the packages cpack makes of BUILD_DIR, its bookworm root cached in
# BUILD_DIR/deb-clean-install (made once, from the Debian mirror); with the build's
# swivel-dxl-emulator, the daemon also drives emulated DYNAMIXEL servos there. Exits 77
# (skipped), saying why, only where this host cannot run it.
set -euo pipefail
build=$1 cpack=$2 source=$3 dxl_emulator=${4:-}
work="$build/deb-clean-install"
skip() { echo "SKIP: $*"; exit 77; }

[[ $EUID -eq 0 ]] || skip "needs root (systemd-nspawn, chroot, debootstrap)"
command -v systemd-nspawn >/dev/null || skip "no systemd-nspawn: tools/setup installs systemd-container"
unshare --mount --pid --fork --mount-proc true 2>/dev/null ||
  skip "this host refuses mount and PID namespaces, which systemd-nspawn needs"
# Every run takes the package's dependencies from the mirror (the root once, too).
timeout 10 bash -c 'exec 3<>/dev/tcp/deb.debian.org/80' 2>/dev/null ||
  skip "deb.debian.org cannot be reached: the package's dependencies come from there"

mkdir -p "$work"
rm -rf "$work/packages"
"$cpack" -G DEB -B "$work/packages" --config "$build/CPackConfig.cmake" >"$work/cpack.log" 2>&1 ||
  { tail -n 30 "$work/cpack.log"; echo "FAIL: cpack -G DEB of $build"; exit 1; }
args=(--systemd --debs "$work/packages" --build-dir "$work")
[[ -z $dxl_emulator ]] || args+=(--dxl-emulator "$dxl_emulator")
exec "$source/tools/deb-clean-install" "${args[@]}"
