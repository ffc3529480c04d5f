#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Lints a systemd unit: fails on a non-zero exit of `systemd-analyze verify` and on any
# output at all, since systemd reports most problems as warnings with exit status 0.
unit="$1"
out=$(systemd-analyze verify "$unit" 2>&1)
rc=$?
if [ $rc -ne 0 ] || [ -n "$out" ]; then
  printf 'systemd-analyze verify %s (exit %s):\n%s\n' "$unit" "$rc" "$out"
  exit 1
fi
echo "systemd-analyze verify $unit: clean"
