# SPDX-License-Identifier: Apache-2.0
# shellcheck shell=bash disable=SC2154  # its variables are set by tools/deb-clean-install
# tools/deb-clean-install --systemd: the swivel package under a real systemd as PID 1.
# Sourced by tools/deb-clean-install once the packages are built; uses its variables
# (runtime_deb, base, root, logs, mirror, run_s, max_exposure, dxl_emulator) and helpers (ok, bad, note,
# abort, phase_done, in_root). A fresh copy of a cached minimal bookworm root with systemd
# gets the package's dependencies from the mirror (chroot, apt-get satisfy), then boots under
# systemd-nspawn with a private network (nothing leaves the container but loopback). Inside:
# apt-get install of the package, `systemctl start swiveld` (Type=notify: active once the
# daemon sent READY=1), swivelctl reading its state, the watchdog, a reload and a stop, and
# `systemd-analyze security` at most max_exposure; the daemon driving emulated DYNAMIXEL
# servos over a serial port; the same with the DDS Security profile and its drop-in; then
# upgrade, remove, reinstall and purge with the service enabled and running.

container_name=swivel-check
# The daemon's loop asks for SCHED_FIFO and mlockall: the container keeps CAP_SYS_NICE by
# default, CAP_IPC_LOCK only when asked.
nspawn_args=(--quiet --boot --directory="$root" --machine="$container_name" --private-network
             --register=no --capability=CAP_IPC_LOCK)
# Without systemd on the host there is no one to make the container a scope unit of its own.
[[ -d /run/systemd/system ]] || nspawn_args+=(--keep-unit)

for tool in systemd-nspawn nsenter unshare; do
  command -v "$tool" >/dev/null ||
    abort "this host lacks $tool (tools/setup installs systemd-container and util-linux)"
done

# --- 2. A clean bookworm root with systemd: the pristine one is cached, every run a copy.
if [[ ! -d $base ]]; then
  echo "== debootstrap bookworm (minbase, systemd) into $base"
  rm -rf "$base.tmp"
  debootstrap --variant=minbase --include=systemd,systemd-sysv bookworm "$base.tmp" "$mirror" \
    >"$logs/debootstrap.log" 2>&1 || abort "debootstrap bookworm from $mirror" "$logs/debootstrap.log"
  mv "$base.tmp" "$base"  # only a finished root gets the cached name
fi
[[ -z $(mounted_under_root) ]] || abort "$root still has mounts from an earlier run: $(mounted_under_root)"
rm -rf "$root"
cp -a "$base" "$root"
cp /etc/resolv.conf "$root/etc/resolv.conf"
# /tmp is a fresh tmpfs in the booted container: the packages wait in /srv.
mkdir -p "$root/srv/debs"
cp "$runtime_deb" "$root/srv/debs/"
deb=/srv/debs/$(basename "$runtime_deb")
version=$(dpkg-deb -f "$runtime_deb" Version)
newer="$version.1"
# The upgrade: the same contents with a higher version.
rm -rf "$build/upgrade"
dpkg-deb -R "$runtime_deb" "$build/upgrade"
sed -i "s/^Version: .*/Version: $newer/" "$build/upgrade/DEBIAN/control"
dpkg-deb --root-owner-group -b "$build/upgrade" "$root/srv/debs/swivel_${newer}.deb" >/dev/null
newer_deb=/srv/debs/swivel_${newer}.deb

# The container has no network: the dependencies come from the mirror before it boots, its
# Recommends (gnuplot-nox, for plots) are left out (the run without --systemd takes them). /proc
# is mounted in a mount namespace of its own, so nothing stays mounted in the root.
in_root_with_proc() {
  unshare --mount --propagation private /bin/sh -c 'mount -t proc proc "$0/proc" && exec chroot "$0" "$@"' \
    "$root" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin LANG=C.UTF-8 DEBIAN_FRONTEND=noninteractive "$@"
}
in_root_with_proc apt-get update >"$logs/apt-update.log" 2>&1 ||
  abort "apt-get update in the root" "$logs/apt-update.log"
depends=$(dpkg-deb -f "$runtime_deb" Depends)
in_root_with_proc apt-get satisfy -y --no-install-recommends "$depends" >"$logs/apt-satisfy.log" 2>&1 ||
  abort "apt-get satisfy of swivel's Depends ($depends)" "$logs/apt-satisfy.log"
ok "clean bookworm root with systemd $(in_root dpkg-query -W -f='${Version}' systemd) and swivel's dependencies from $mirror"
phase_done root

# --- 3. Boot it.
echo "== booting the root under systemd-nspawn (private network)"
systemd-nspawn "${nspawn_args[@]}" >"$logs/container-console.log" 2>&1 </dev/null &
container_pid=$!
leader=""
for _ in $(seq 100); do
  leader=$(pgrep -P "$container_pid" -x systemd || true)
  [[ -n $leader ]] && break
  kill -0 "$container_pid" 2>/dev/null || break
  sleep 0.1
done
[[ -n $leader ]] || abort "systemd-nspawn started no systemd in $root" "$logs/container-console.log"
# in_box COMMAND...: runs COMMAND in the booted container (its namespaces, its root), as root.
in_box() { nsenter --target "$leader" --all /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin LANG=C.UTF-8 "$@"; }
# systemctl reaches PID 1 only once it listens on its socket: until then, ask again.
system_state=""
deadline=$((SECONDS + 60))
while [[ $SECONDS -lt $deadline ]]; do
  system_state=$(timeout 60 nsenter --target "$leader" --all systemctl is-system-running --wait 2>&1 || true)
  [[ $system_state == 'Failed to connect to bus'* ]] || break
  sleep 0.2
done
case "$system_state" in
  running) ok "the container booted: systemd $(in_box systemctl --version | head -n 1 | cut -d' ' -f2) as PID 1, system running" ;;
  degraded) note "the container booted degraded; failed units: $(in_box systemctl --failed --plain --no-legend | awk '{print $1}' | paste -sd' ')" ;;
  *) abort "the container's systemd did not finish booting: '$system_state'" "$logs/container-console.log" ;;
esac
links=$(in_box ls /sys/class/net | paste -sd' ')
[[ -z $links || $links == lo ]] && ok "the container's network: ${links:-lo} only" ||
  bad "the container has network interfaces besides lo: $links"
phase_done boot

# --- 4. Install, start, check, stop.
echo "== apt-get install $deb in the booted container"
in_box DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "$deb" >"$logs/apt-install.log" 2>&1 ||
  abort "apt-get install $deb in the container" "$logs/apt-install.log"
unit_state=$(in_box systemctl show -P LoadState swiveld.service)
[[ $unit_state == loaded ]] &&
  ok "apt-get install under systemd: swiveld.service $unit_state ($(in_box systemctl show -P FragmentPath swiveld.service))" ||
  abort "after the install swiveld.service is '$unit_state' (postinst's daemon-reload?)"
in_box systemd-analyze verify --man=no swiveld.service >"$logs/verify.log" 2>&1 && [[ ! -s $logs/verify.log ]] &&
  ok "systemd-analyze verify swiveld.service in the container: clean" ||
  bad "systemd-analyze verify swiveld.service:"$'\n'"$(sed 's/^/  /' "$logs/verify.log")"

# unit_show PROPERTY: the value systemd holds for swiveld.service.
unit_show() { in_box systemctl show -P "$1" swiveld.service; }
# expect_running WHAT: the service is active (running), or the check ends with its journal.
expect_running() {
  local state
  state="$(unit_show ActiveState) ($(unit_show SubState))"
  if [[ $state == 'active (running)' ]]; then
    ok "$1: active (running), status \"$(unit_show StatusText)\""
  else
    in_box journalctl -u swiveld.service --no-pager -n 30 >"$logs/journal-failed.log" 2>&1
    abort "$1: swiveld.service is $state, result $(unit_show Result)" "$logs/journal-failed.log"
  fi
}
# journal_has PID TEXT LOG: TEXT is in what process PID logged (journald may write it a moment
# later); the log of PID is left in LOG.
journal_has() {
  local _
  for _ in $(seq 30); do
    in_box journalctl --no-pager -o cat _PID="$1" >"$logs/$3" 2>&1
    grep -qF -- "$2" "$logs/$3" && return 0
    sleep 0.1
  done
  return 1
}
# start_or_abort LOG WHAT: systemctl start swiveld, or the check ends with the unit's status
# and the last lines of its journal (journald may write the failing process's lines a moment
# after systemctl returns).
start_or_abort() {
  in_box systemctl start swiveld.service >"$logs/$1.log" 2>&1 && return 0
  sleep 1
  # (systemctl status exits 3 for a unit that is not running.)
  { in_box systemctl status --no-pager -n 0 swiveld.service || true
    in_box journalctl -u swiveld.service --no-pager -n 15 -o cat || true; } >>"$logs/$1.log" 2>&1
  abort "$2" "$logs/$1.log"
}
# exposure: the overall exposure systemd-analyze security gives the loaded unit.
exposure() {
  in_box systemd-analyze security --no-pager swiveld.service >"$logs/security-$1.log" 2>&1 || true
  sed -n 's/.*Overall exposure level for swiveld.service: \([0-9.]*\).*/\1/p' "$logs/security-$1.log"
}
expect_exposure() {  # expect_exposure LOG-NAME WHAT: the score also in last_score
  local score
  score=$(exposure "$1")
  last_score=$score
  if [[ -z $score ]]; then
    bad "systemd-analyze security ($2) gave no overall exposure:"$'\n'"$(tail -n 5 "$logs/security-$1.log" | sed 's/^/  /')"
  elif awk -v s="$score" -v m="$max_exposure" 'BEGIN {exit !(s <= m)}'; then
    ok "systemd-analyze security swiveld.service ($2): exposure $score (at most $max_exposure)"
  else
    bad "systemd-analyze security swiveld.service ($2): exposure $score, above $max_exposure; the settings it counts:"$'\n'"$(grep '✗' "$logs/security-$1.log" | sed 's/^/  /')"
  fi
}

echo "== systemctl start swiveld"
t0=$SECONDS
start_or_abort start "systemctl start swiveld"
expect_running "systemctl start swiveld (Type=notify: READY=1) in $((SECONDS - t0)) s"
main_pid=$(unit_show MainPID)
journal_has "$main_pid" 'CYCLONEDDS_URI=file:///etc/swivel/dds/cyclonedds.xml (environment' journal.log &&
  ok "DDS configuration in effect: the unit's file:///etc/swivel/dds/cyclonedds.xml" ||
  bad "swiveld does not report the unit's CYCLONEDDS_URI:"$'\n'"$(grep -m3 'DDS' "$logs/journal.log" | sed 's/^/  /')"
if in_box swivelctl echo state --count 3 --json --timeout 10 >"$logs/state.json" 2>"$logs/swivelctl.log" &&
   [[ $(grep -c '"cycle"' "$logs/state.json") -eq 3 ]]; then
  ok "swivelctl echo state in the container: 3 samples over loopback DDS, $(head -n 1 "$logs/state.json" | grep -oE '"(robot_id|mode)": ?[^,]*' | tr '\n' ' ')"
else
  bad "swivelctl echo state received no state from the service:"$'\n'"$(cat "$logs/swivelctl.log" "$logs/state.json" | tail -n 5 | sed 's/^/  /')"
fi
# The sandbox leaves the loop its real-time settings: a SCHED_FIFO thread and locked memory.
fifo=$(in_box ps -L -o cls=,rtprio=,comm= -p "$main_pid" | awk '$1 == "FF" {print $3 " prio " $2}' | paste -sd, -)
locked=$(in_box grep VmLck "/proc/$main_pid/status" | awk '{print $2}')
rt_warnings=$(grep -iE 'sched_fifo|mlockall|real-?time' "$logs/journal.log" | head -n 3 | sed 's/^/  /' || true)
if [[ -n $fifo && ${locked:-0} -gt 0 ]]; then
  ok "real-time under the sandbox: SCHED_FIFO thread $fifo, $((locked / 1024)) MiB locked"
else
  bad "the loop lost its real-time settings under the unit (SCHED_FIFO: ${fifo:-none}, VmLck ${locked:-?} kB):"$'\n'"${rt_warnings:-  (no warning from swiveld)}"
fi
device_allow=$(unit_show DeviceAllow)
[[ -z $device_allow ]] && ok "no device allow-list: /dev/cpu_dma_latency and serial ports stay reachable" ||
  bad "the unit restricts devices to '$device_allow': the loop's /dev/cpu_dma_latency and serial port would be refused"

watchdog_before=$(unit_show WatchdogTimestampMonotonic)
sleep "$run_s"
watchdog_after=$(unit_show WatchdogTimestampMonotonic)
if [[ $(unit_show MainPID) == "$main_pid" && $(unit_show NRestarts) == 0 && $watchdog_after -gt $watchdog_before ]]; then
  ok "after ${run_s} s: the same process, no restart, WATCHDOG=1 still arriving (WatchdogSec=$(unit_show WatchdogUSec))"
else
  bad "after ${run_s} s: MainPID $(unit_show MainPID) (was $main_pid), NRestarts $(unit_show NRestarts), watchdog timestamps $watchdog_before -> $watchdog_after"
fi
in_box systemctl reload swiveld.service >"$logs/reload.log" 2>&1 || bad "systemctl reload swiveld: $(cat "$logs/reload.log")"
sleep 1
[[ $(unit_show MainPID) == "$main_pid" ]] && expect_running "systemctl reload swiveld (SIGHUP)" ||
  bad "systemctl reload swiveld: MainPID $(unit_show MainPID), was $main_pid"
expect_exposure running "the packaged unit, daemon running"
running_score=$last_score

in_box systemctl stop swiveld.service >"$logs/stop.log" 2>&1 || bad "systemctl stop swiveld: $(cat "$logs/stop.log")"
stop_result="$(unit_show ActiveState) $(unit_show Result) $(unit_show ExecMainStatus)"
if [[ $stop_result == 'inactive success 0' ]] && journal_has "$main_pid" 'stopped cleanly' journal.log; then
  ok "systemctl stop swiveld: inactive, exit 0, \"$(grep -m1 -o 'stopped cleanly.*' "$logs/journal.log")\""
else
  bad "systemctl stop swiveld: $stop_result (state, result, exit status):"$'\n'"$(tail -n 5 "$logs/journal.log" | sed 's/^/  /')"
fi
phase_done run

# --- 4b. The DYNAMIXEL serial bus under the sandbox: the packaged daemon and plugin on two
# servos that swivel-dxl-emulator (of the build, not packaged) answers for on a
# pseudo-terminal, a runtime drop-in pointing ExecStart= at a configuration using it. The
# port is root:dialout 0660, as a USB serial adapter's.
if [[ -n $dxl_emulator ]]; then
  echo "== the DYNAMIXEL bus: swiveld on emulated servos"
  install -m 755 "$dxl_emulator" "$root/srv/swivel-dxl-emulator"
  in_box systemd-run --quiet --unit=swivel-dxl-emulator -p RuntimeDirectory=swivel-dxl \
    /srv/swivel-dxl-emulator --ids 1,2 --link /run/swivel-dxl/port >"$logs/dxl-emulator.log" 2>&1 ||
    abort "systemd-run swivel-dxl-emulator" "$logs/dxl-emulator.log"
  for _ in $(seq 50); do in_box test -L /run/swivel-dxl/port && break; sleep 0.1; done
  if ! in_box test -L /run/swivel-dxl/port; then
    in_box journalctl -u swivel-dxl-emulator.service --no-pager -n 10 >>"$logs/dxl-emulator.log" 2>&1
    abort "$dxl_emulator made no /run/swivel-dxl/port in the container" "$logs/dxl-emulator.log"
  fi
  # As Debian gives a USB serial adapter: root's, read and written by the dialout group.
  in_box sh -c 'chgrp dialout "$(readlink /run/swivel-dxl/port)" && chmod 660 "$(readlink /run/swivel-dxl/port)"'
  # The longest reply timeout the plugin takes: the emulator is an ordinary process, late on
  # a loaded machine, and the bus's timing is not what this checks.
  cat >"$root/etc/swivel/swiveld-dxl.yaml" <<'YAML'
loop: {rate_hz: 500}
robot_model: /etc/swivel/robots/docent.yaml
hardware:
  plugin: dynamixel
  params: {port: /run/swivel-dxl/port, reply_timeout_s: 1.0, stale_timeout_s: 3.0, left: {id: 1}, right: {id: 2, direction: -1}}
drivetrain: {plugin: differential, params: {max_wheel_rate_radps: 20.0}}
localization: {plugin: raw_eg, params: {heading_source: encoders}}
command: {timeout_s: 0.5, source: none}
YAML
  in_box mkdir -p /run/systemd/system/swiveld.service.d
  printf '[Service]\nExecStart=\nExecStart=/usr/bin/swiveld --config /etc/swivel/swiveld-dxl.yaml\n' \
    >"$logs/dxl-dropin.conf"
  in_box tee /run/systemd/system/swiveld.service.d/dxl.conf <"$logs/dxl-dropin.conf" >/dev/null
  in_box systemctl daemon-reload
  start_or_abort start-dxl "systemctl start swiveld on the DYNAMIXEL bus"
  expect_running "systemctl start swiveld on emulated DYNAMIXEL servos"
  journal_has "$(unit_show MainPID)" 'hardware dynamixel activated' journal-dxl.log &&
    ok "the dynamixel plugin opened the serial port and found its servos: $(grep -c 'swiveld info: dynamixel ID' "$logs/journal-dxl.log") of 2" ||
    bad "the dynamixel plugin did not start on /run/swivel-dxl/port:"$'\n'"$(tail -n 5 "$logs/journal-dxl.log" | sed 's/^/  /')"
  # Driving 0.2 m/s for 1.5 s: the pose comes from the servos' encoders over the bus.
  in_box swivelctl drive 0.2 0 0 --for 1.5 >"$logs/dxl-drive.log" 2>&1 || bad "swivelctl drive: $(cat "$logs/dxl-drive.log")"
  sleep 0.5
  in_box swivelctl echo state --count 1 --json --timeout 5 >"$logs/dxl-state.json" 2>&1 || true
  x=$(grep -oE '"x_m": ?[-0-9.e]+' "$logs/dxl-state.json" | grep -oE '[-0-9.e]+$' || true)
  fault=$(grep -oE '"fault": ?"[^"]*"' "$logs/dxl-state.json" | cut -d'"' -f4 || true)
  if [[ -n $x && $fault == none ]] && awk -v x="$x" 'BEGIN {exit !(x > 0.2 && x < 0.4)}'; then
    ok "swivelctl drive 0.2 m/s for 1.5 s: the encoders put the robot at x = $x m, no fault"
  else
    bad "after swivelctl drive 0.2 m/s for 1.5 s: x = ${x:-?} m (expected about 0.3), fault ${fault:-?}"
  fi
  expect_exposure dxl "on the DYNAMIXEL bus, daemon running"
  # The daemon first: it brings the servos to rest over the bus before it exits.
  dxl_pid=$(unit_show MainPID)
  in_box systemctl stop swiveld.service >/dev/null 2>&1 || true
  if [[ $(unit_show Result) == success && $(unit_show ExecMainStatus) == 0 ]]; then
    ok "systemctl stop swiveld on the DYNAMIXEL bus: exit 0"
  else
    in_box journalctl --no-pager -o cat _PID="$dxl_pid" >"$logs/journal-dxl.log" 2>&1 || true
    bad "systemctl stop swiveld on the DYNAMIXEL bus: $(unit_show Result), status $(unit_show ExecMainStatus):"$'\n'"$(tail -n 5 "$logs/journal-dxl.log" | sed 's/^/  /')"
  fi
  in_box systemctl stop swivel-dxl-emulator.service >/dev/null 2>&1 || true
  in_box rm -f /run/systemd/system/swiveld.service.d/dxl.conf /etc/swivel/swiveld-dxl.yaml
  in_box systemctl daemon-reload
  phase_done dynamixel
else
  note "the DYNAMIXEL bus under the sandbox was not run (--dxl-emulator names no swivel-dxl-emulator)"
fi

# --- 5. The DDS Security profile and its drop-in.
echo "== DDS Security: make_profile.sh /etc/swivel/security, the secure drop-in"
security=/etc/swivel/security
scripts=$(in_box dpkg -L swivel | grep -m1 '/swivel/security/make_profile.sh$' || true)
[[ -n $scripts ]] || abort "the package has no make_profile.sh"
in_box "$scripts" "$security" >"$logs/make-profile.log" 2>&1 || abort "$scripts $security" "$logs/make-profile.log"
dropin_src=$(in_box dpkg -L swivel | grep -m1 '/swivel/security/secure-dropin.conf$' || true)
[[ -n $dropin_src ]] || abort "the package has no secure-dropin.conf"
in_box install -D -m 644 "$dropin_src" /etc/systemd/system/swiveld.service.d/secure.conf
in_box systemctl daemon-reload
secure_uri=file://$security/identities/swiveld/cyclonedds.xml
[[ $(unit_show Environment) == *"CYCLONEDDS_URI=$secure_uri"* ]] ||
  bad "with the drop-in systemd gives swiveld $(unit_show Environment), not CYCLONEDDS_URI=$secure_uri"
start_or_abort start-secure "systemctl start swiveld with the drop-in"
expect_running "systemctl start swiveld with the secure drop-in"
journal_has "$(unit_show MainPID)" "CYCLONEDDS_URI=$secure_uri (environment" journal-secure.log &&
  ok "secured swiveld's DDS configuration: $secure_uri" ||
  bad "secured swiveld does not report CYCLONEDDS_URI=$secure_uri"
if in_box CYCLONEDDS_URI="file://$security/identities/swivelctl/cyclonedds.xml" swivelctl echo state \
     --count 1 --json --timeout 15 >"$logs/secure-state.json" 2>"$logs/secure-swivelctl.log" &&
   grep -q '"cycle"' "$logs/secure-state.json"; then
  ok "swivelctl with the profile's client identity reads the secured service's state"
else
  bad "swivelctl with the client identity reads no state:"$'\n'"$(tail -n 5 "$logs/secure-swivelctl.log" | sed 's/^/  /')"
fi
if in_box swivelctl echo state --count 1 --timeout 3 >"$logs/plain-state.log" 2>&1; then
  bad "swivelctl without the profile reads the secured service's state"
else
  ok "swivelctl without the profile reads nothing from the secured service"
fi
expect_exposure secure "with the secure drop-in, daemon running"
secure_score=$last_score
phase_done security

# --- 6. The package's life under systemd, the service enabled, running and secured.
echo "== upgrade, remove, reinstall, purge (service enabled and running)"
in_box systemctl enable swiveld.service >"$logs/enable.log" 2>&1 || bad "systemctl enable swiveld: $(cat "$logs/enable.log")"
pid_before=$(unit_show MainPID)
echo "# kept across upgrades" >>"$root/etc/swivel/swiveld.yaml"
in_box DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "$newer_deb" >"$logs/apt-upgrade.log" 2>&1 ||
  abort "apt-get install swivel $newer (upgrade)" "$logs/apt-upgrade.log"
# postinst try-restarts a running service: a new process, the drop-in still in effect.
if [[ $(in_box dpkg-query -W -f='${Version}' swivel) == "$newer" && $(unit_show MainPID) != "$pid_before" ]] &&
   grep -q '^# kept across upgrades' "$root/etc/swivel/swiveld.yaml" &&
   [[ $(unit_show Environment) == *"CYCLONEDDS_URI=$secure_uri"* ]]; then
  expect_running "upgrade $version -> $newer: restarted (MainPID $pid_before -> $(unit_show MainPID)), edited swiveld.yaml and drop-in kept"
else
  bad "upgrade $version -> $newer: version $(in_box dpkg-query -W -f='${Version}' swivel), MainPID $pid_before -> $(unit_show MainPID), edit kept: $(grep -c '^# kept' "$root/etc/swivel/swiveld.yaml")"
fi
in_box DEBIAN_FRONTEND=noninteractive apt-get remove -y swivel >"$logs/apt-remove.log" 2>&1 ||
  abort "apt-get remove swivel" "$logs/apt-remove.log"
# prerm stops the service; postrm's daemon-reload forgets the unit.
if [[ $(unit_show ActiveState) == inactive && $(unit_show LoadState) == not-found && ! -e $root/usr/bin/swiveld &&
      -f $root/etc/swivel/swiveld.yaml ]] && in_box getent passwd swivel >/dev/null; then
  ok "remove: the service stopped and its unit gone, /etc/swivel and the swivel user stay"
else
  bad "remove: swiveld.service $(unit_show ActiveState)/$(unit_show LoadState), swiveld present: $([[ -e $root/usr/bin/swiveld ]] && echo yes || echo no), swiveld.yaml kept: $([[ -f $root/etc/swivel/swiveld.yaml ]] && echo yes || echo no)"
fi
in_box DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "$newer_deb" >"$logs/apt-reinstall.log" 2>&1 ||
  abort "apt-get install swivel (reinstall)" "$logs/apt-reinstall.log"
start_or_abort start-reinstalled "systemctl start swiveld after the reinstall"
expect_running "reinstall: enabled $(in_box systemctl is-enabled swiveld.service 2>&1), started on the kept configuration"
expect_exposure reinstalled "reinstalled, with the drop-in, daemon running"
in_box DEBIAN_FRONTEND=noninteractive apt-get purge -y swivel >"$logs/apt-purge.log" 2>&1 ||
  abort "apt-get purge swivel" "$logs/apt-purge.log"
# The profile and the drop-in are the administrator's files, not the package's: they stay.
left=$(in_box find /etc/swivel /var/lib/swivel /var/log/swivel -mindepth 1 -maxdepth 1 2>/dev/null | grep -vx "$security" | tr '\n' ' ' || true)
wants=$(in_box find /etc/systemd/system -name swiveld.service 2>/dev/null | tr '\n' ' ' || true)
if [[ -z $left && -z $wants && $(unit_show ActiveState) == inactive ]] && ! in_box pgrep -x swiveld >/dev/null; then
  ok "purge: the service stopped, its enablement, configuration and state gone ($security and the drop-in stay)"
else
  bad "purge: swiveld.service $(unit_show ActiveState), left: ${left}${wants}"
fi
phase_done lifecycle

echo "== powering the container off"
in_box systemctl poweroff >/dev/null 2>&1 || true
for _ in $(seq 300); do kill -0 "$container_pid" 2>/dev/null || break; sleep 0.1; done
if kill -0 "$container_pid" 2>/dev/null; then
  bad "the container did not power off within 30 s"
else
  wait "$container_pid" || true
  container_pid=""
  ok "the container powered off"
fi
note "exposure with the daemon running: ${running_score:-?} (packaged unit), ${secure_score:-?} (with the secure drop-in)"
phase_done poweroff
