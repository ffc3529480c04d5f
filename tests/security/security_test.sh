#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The DDS Security cases. Each starts secure_peer processes with real credentials from the
# fixture's profile; a stand-in robot plays the daemon (identity swiveld).
# Usage: security_test.sh CASE   (environment from tests/security/CMakeLists.txt)
set -euo pipefail
case=$1
profile=${SWIVEL_SECURITY_PROFILE:?}
peer=${SWIVEL_SECURE_PEER:?}
scripts=${SWIVEL_SECURITY_SCRIPTS:?}
loopback=${SWIVEL_LOOPBACK_CONFIG:?}
source_dir=${SWIVEL_SOURCE_DIR:?}

work=$(mktemp -d)
robot_pid=""
cleanup() {
  if [[ -n "$robot_pid" ]] && kill -0 "$robot_pid" 2>/dev/null; then
    kill -TERM "$robot_pid" 2>/dev/null || true
    wait "$robot_pid" 2>/dev/null || true
  fi
  rm -rf "$work"
}
trap cleanup EXIT

fail() {
  echo "FAIL: $*" >&2
  exit 1
}

config() { echo "file://$profile/identities/$1/cyclonedds.xml"; }
daemon=$(config swiveld)
client=$(config swivelctl)
observer=$(config swivelobs)
rogue="file://$profile/rogue/identities/swivelctl/cyclonedds.xml"
plain="file://$loopback"

# expect STATUS WHAT URI ARGS...: runs secure_peer ARGS with configuration URI and requires
# exit status STATUS; its output stays in $work/out and $work/err for further checks.
expect() {
  local want=$1 what=$2 uri=$3
  shift 3
  local got=0
  CYCLONEDDS_URI=$uri "$peer" "$@" >"$work/out" 2>"$work/err" || got=$?
  sed 's/^/    /' "$work/out" "$work/err"
  [[ "$got" == "$want" ]] || fail "$what: secure_peer $* exited $got, expected $want"
  echo "ok: $what"
}

start_robot() {
  CYCLONEDDS_URI=$daemon "$peer" robot 100 >"$work/robot.log" 2>&1 &
  robot_pid=$!
  for _ in $(seq 100); do
    grep -q '^robot: up' "$work/robot.log" && return 0
    kill -0 "$robot_pid" 2>/dev/null || break
    sleep 0.1
  done
  cat "$work/robot.log" >&2
  fail "the robot (identity swiveld) did not start"
}

stop_robot() {
  kill -TERM "$robot_pid"
  wait "$robot_pid" || fail "the robot exited with an error"
  robot_pid=""
  sed 's/^/    robot| /' "$work/robot.log"
}

case_trusted_client_reads_pose_and_drives() {
  start_robot
  expect 0 "trusted client reads the pose within 10 s" "$client" watch 10
  expect 0 "trusted client's command moves the robot within 10 s" "$client" drive 10 0.5
  stop_robot
  grep -q '^command: vx_m_s=0.500' "$work/robot.log" ||
    fail "the robot log shows no command from the trusted client"
}

case_untrusted_peers_neither_read_nor_write() {
  start_robot
  # Control: the robot is up and readable, so silence below is the security at work.
  expect 0 "trusted client reads the pose" "$client" watch 10
  expect 0 "identity from another CA reads nothing for 3 s" "$rogue" watch-none 3
  cp "$work/err" "$work/rogue.err"
  expect 0 "participant without security reads nothing for 3 s" "$plain" watch-none 3
  expect 0 "identity from another CA publishes commands for 3 s" "$rogue" inject 3 9.0
  grep -q ', 0 matched readers' "$work/out" || fail "the rogue writer matched a reader"
  cat "$work/err" >>"$work/rogue.err"
  expect 0 "participant without security publishes commands for 3 s" "$plain" inject 3 9.0
  grep -q ', 0 matched readers' "$work/out" || fail "the unsecured writer matched a reader"
  # Any command that had arrived would have moved the robot for half a second.
  expect 0 "the robot has not moved" "$client" still 10
  stop_robot
  if grep -q '^command:' "$work/robot.log"; then
    fail "the robot received commands from a participant without valid credentials"
  fi
  grep -q '^robot: commands=0 ' "$work/robot.log" || fail "the robot did not report 0 commands"
  # The rogue was seen and turned away by authentication, not merely never discovered;
  # whichever side started the handshake, one of the two logs says so.
  grep -q 'handshake.*failed: Certificate not valid' "$work/robot.log" "$work/rogue.err" ||
    fail "no log shows a handshake refused for the identity of another CA"
}

# Copies FILE to OUT with the first "<max>230</max>" made "<max>231</max>": one byte, after
# signing, widening the domain range the document claims.
tamper() {
  local file=$1 out=$2
  sed '0,/<max>230<\/max>/s//<max>231<\/max>/' "$file" >"$out"
  [[ $(cmp -l "$file" "$out" | wc -l) == 1 ]] || fail "tampering $file did not change one byte"
}

case_tampered_documents_are_refused() {
  local identity="$profile/identities/swivelctl"
  tamper "$identity/permissions.p7s" "$work/permissions.p7s"
  sed "s|file:$identity/permissions.p7s|file:$work/permissions.p7s|" "$identity/cyclonedds.xml" \
    >"$work/tampered_permissions.xml"
  grep -q "$work/permissions.p7s" "$work/tampered_permissions.xml" ||
    fail "the tampered configuration does not use the tampered permissions"
  expect 0 "the untouched configuration is accepted" "$client" writer command
  expect 2 "tampered permissions are refused" "file://$work/tampered_permissions.xml" \
    writer command
  grep -q 'secure_peer: dds_create_participant failed' "$work/err" ||
    fail "participant creation did not fail"
  grep -q 'Error occurred while validating local permissions' "$work/err" ||
    fail "Cyclone's log does not name the permissions"
  grep -q 'PKCS7_signatureVerify:digest failure' "$work/err" ||
    fail "Cyclone's log does not name the broken signature"

  tamper "$profile/governance.p7s" "$work/governance.p7s"
  sed "s|file:$profile/governance.p7s|file:$work/governance.p7s|" "$identity/cyclonedds.xml" \
    >"$work/tampered_governance.xml"
  expect 2 "tampered governance is refused" "file://$work/tampered_governance.xml" \
    writer command
  grep -q 'PKCS7_signatureVerify:digest failure' "$work/err" ||
    fail "Cyclone's log does not name the broken signature"
}

case_roles_limit_what_each_identity_may_do() {
  expect 0 "daemon may publish state" "$daemon" writer state
  expect 3 "daemon may not publish commands" "$daemon" writer command
  expect 0 "client may publish commands" "$client" writer command
  expect 3 "client may not publish state" "$client" writer state
  expect 3 "observer may not publish commands" "$observer" writer command
  expect 3 "observer may not publish state" "$observer" writer state
  grep -q 'Not Allowed By Security' "$work/err" || fail "refusal does not name security"
  start_robot
  expect 0 "observer reads the pose within 10 s" "$observer" watch 10
  stop_robot
}

# What ROLE may do with TOPIC: prints "w" when a writer may be created, "r" for a reader.
access() {
  local uri=$1 topic=$2 kind grants="" got
  for kind in writer reader; do
    got=0
    SWIVEL_TEST_STATE_TOPIC=$topic CYCLONEDDS_URI=$uri "$peer" "$kind" state \
      >/dev/null 2>"$work/err" || got=$?
    case "$got" in
      0) grants+=${kind:0:1} ;;
      3) ;;
      *) cat "$work/err" >&2; fail "secure_peer $kind on $topic exited $got" ;;
    esac
  done
  echo "${grants:--}"
}

# Every topic the bridge declares is in exactly one family, with the grants of the role table.
case_permissions_cover_every_bridge_topic() {
  local header="$source_dir/core/include/swivel/dds/topics.hpp"
  local -a topics
  if [[ -f "$header" ]]; then
    mapfile -t topics < <(sed -n 's/^inline constexpr const char\* k[A-Za-z]*Topic = "\(.*\)";$/\1/p' "$header")
    [[ ${#topics[@]} -gt 0 ]] || fail "no topic names found in $header"
  fi
  # The ROS 2 names, without and with a namespace (core/dds/src/options.cpp).
  topics+=(rt/odom rt/robot1/odom rt/cmd_vel rt/robot1/cmd_vel rt/initialpose rt/robot1/initialpose
           rt/tf rt/diagnostics rt/joint_states rt/robot1/joint_states)
  local topic daemon_grants client_grants observer_grants
  for topic in "${topics[@]}"; do
    daemon_grants=$(access "$daemon" "$topic")
    client_grants=$(access "$client" "$topic")
    observer_grants=$(access "$observer" "$topic")
    case "$daemon_grants/$client_grants/$observer_grants" in
      w/r/r) echo "ok: $topic is state (daemon writes; client and observer read)" ;;
      r/w/-) echo "ok: $topic is a command (client writes; daemon reads; observer nothing)" ;;
      *) fail "$topic: daemon '$daemon_grants', client '$client_grants', observer" \
        "'$observer_grants' fits neither the state nor the command family" ;;
    esac
  done
  # And the families are what the daemon's interface says they are.
  [[ $(access "$daemon" swivel_robot_state) == w ]] || fail "robot state is not state"
  [[ $(access "$daemon" swivel_velocity_command) == r ]] || fail "velocity is not a command"
  [[ $(access "$daemon" nonexistent_topic) == - ]] || fail "an unlisted topic is not denied"
}

case_profile_scripts_are_idempotent() {
  local dir="$work/profile"
  "$scripts/make_profile.sh" "$dir" >/dev/null
  (cd "$dir" && find . -type f -exec sha256sum {} + | sort) >"$work/before"
  "$scripts/make_profile.sh" "$dir" >"$work/second_run"
  (cd "$dir" && find . -type f -exec sha256sum {} + | sort) >"$work/after"
  cmp -s "$work/before" "$work/after" || fail "re-running make_profile.sh changed the profile"
  if grep -q '^created' "$work/second_run"; then
    fail "re-running make_profile.sh recreated something"
  fi
  echo "ok: re-running make_profile.sh leaves the profile unchanged"

  [[ $(stat -c %a "$dir/ca/identity_ca_key.pem") == 600 ]] || fail "CA key is not private"
  [[ $(stat -c %a "$dir/identities/swiveld/key.pem") == 600 ]] || fail "identity key not private"
  openssl verify -CAfile "$dir/ca/identity_ca.pem" "$dir/identities/swivelctl/cert.pem" ||
    fail "client certificate does not verify against the identity CA"
  [[ $(openssl x509 -in "$dir/identities/swivelctl/cert.pem" -noout -subject) == \
    "subject=CN = swivelctl" ]] || fail "client certificate subject is not CN=swivelctl"
  grep -q '<NetworkInterface name="lo" multicast="true"/>' \
    "$dir/identities/swiveld/cyclonedds.xml" || fail "rendered configuration leaves loopback"

  local got=0
  "$scripts/make_permissions.sh" swivelctl admin "$dir" 2>"$work/err" || got=$?
  { [[ $got != 0 ]] && grep -q "role must be daemon, client or observer, not 'admin'" "$work/err"; } ||
    fail "an unknown role is not refused clearly"
  got=0
  "$scripts/make_identity.sh" 'bad/name' "$dir" 2>"$work/err" || got=$?
  { [[ $got != 0 ]] && grep -q "identity name 'bad/name' must match" "$work/err"; } ||
    fail "an unsafe identity name is not refused clearly"
  echo "ok: bad roles and names are refused"
}

# The service as installed, with the documented drop-in (services/security/secure-dropin.conf):
# the real swiveld, whose installed swiveld.yaml also names dds.config (loopback), must run
# secured, so a participant without the profile's credentials neither reads nor commands it.
case_installed_service_with_secure_dropin_refuses_strangers() {
  local unit=${SWIVEL_INSTALLED_UNIT:?} installed=${SWIVEL_INSTALLED_CONFIG:?}
  local swiveld=${SWIVEL_SWIVELD:?} swivelctl=${SWIVEL_SWIVELCTL:?}
  local dropin="$scripts/secure-dropin.conf" domain=${SWIVEL_TEST_DOMAIN:?}
  # The service's environment as systemd builds it: the unit's Environment= lines, then the
  # drop-in's; the last assignment of a variable wins.
  local uri
  uri=$(sed -n 's/^Environment=CYCLONEDDS_URI=//p' "$unit" "$dropin" | tail -n 1)
  [[ $uri == file:///etc/swivel/security/identities/swiveld/cyclonedds.xml ]] ||
    fail "unit + drop-in give CYCLONEDDS_URI='$uri', not the profile's daemon configuration"
  uri=${uri//\/etc\/swivel\/security/$profile}  # the test's profile stands in for /etc's

  # The installed layout: swiveld.yaml with robots/ and dds/ beside it, on this case's domain.
  local etc="$work/etc/swivel"
  mkdir -p "$etc"
  cp -r "$source_dir/config/robots" "$source_dir/config/dds" "$etc/"
  sed -e "s/^  domain_id: 0 /  domain_id: $domain /" -e 's/^  realtime: true /  realtime: false /' \
    "$installed" >"$etc/swiveld.yaml"
  grep -q '^  source: none ' "$etc/swiveld.yaml" ||
    fail "the installed configuration drives from a script at start-up"
  grep -q '^  config: dds/loopback.xml ' "$etc/swiveld.yaml" ||
    fail "the installed configuration no longer names dds.config: this case tests that conflict"
  grep -q "^  domain_id: $domain " "$etc/swiveld.yaml" || fail "could not move to domain $domain"

  CYCLONEDDS_URI=$uri "$swiveld" --config "$etc/swiveld.yaml" >"$work/robot.log" 2>&1 &
  robot_pid=$!
  local up=0
  for _ in $(seq 200); do
    grep -q 'DDS: robot' "$work/robot.log" && { up=1; break; }
    kill -0 "$robot_pid" 2>/dev/null || break
    sleep 0.1
  done
  [[ $up == 1 ]] || { cat "$work/robot.log" >&2; fail "swiveld did not start"; }
  grep 'DDS: robot' "$work/robot.log"
  grep -q "CYCLONEDDS_URI=$uri (environment; it overrides dds.config file://$etc/dds/loopback.xml)" \
    "$work/robot.log" || fail "swiveld's log does not say that the environment overrides dds.config"

  # ctl URI EXPECTED WHAT ARGS...: swivelctl on this domain with configuration URI.
  ctl() {
    local with=$1 want=$2 what=$3 got=0
    shift 3
    CYCLONEDDS_URI=$with "$swivelctl" "$@" --domain "$domain" >"$work/out" 2>"$work/err" || got=$?
    sed 's/^/    /' "$work/out" "$work/err" | head -n 5
    if [[ $want == 0 ]]; then
      [[ $got == 0 ]] || fail "$what: swivelctl $* exited $got, expected 0"
    else
      [[ $got != 0 ]] || fail "$what: swivelctl $* succeeded"
    fi
    echo "ok: $what"
  }
  ctl "$client" 0 "trusted client reads the pose" echo state --json --count 1 --timeout 15
  local before
  before=$(grep -o '"x_m":[^,]*' "$work/out" | head -n 1)
  ctl "$plain" 1 "participant without security reads nothing" echo state --count 1 --timeout 3
  ctl "$rogue" 1 "identity from another CA reads nothing" echo state --count 1 --timeout 3
  # Commands from a stranger reach no reader: the robot stays where it is.
  CYCLONEDDS_URI=$plain "$swivelctl" drive 0.5 0 0 --for 1.5 --domain "$domain" \
    >"$work/out" 2>&1 || true
  ctl "$client" 0 "trusted client reads the pose again" echo state --json --count 1 --timeout 15
  local after
  after=$(grep -o '"x_m":[^,]*' "$work/out" | head -n 1)
  [[ -n $before && $before == "$after" ]] ||
    fail "the robot moved on a stranger's command ($before -> $after)"
  echo "ok: the robot has not moved ($after)"
  kill -TERM "$robot_pid"
  wait "$robot_pid" || fail "swiveld exited with an error"
  robot_pid=""
}

"case_$case"
