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
service_user=""  # a system user a case created, removed (with its group) at the end
cleanup() {
  if [[ -n "$robot_pid" ]] && kill -0 "$robot_pid" 2>/dev/null; then
    kill -TERM "$robot_pid" 2>/dev/null || true
    wait "$robot_pid" 2>/dev/null || true
  fi
  rm -rf "$work"
  if [[ -n "$service_user" ]]; then
    userdel "$service_user" 2>/dev/null || true
    groupdel "$service_user" 2>/dev/null || true
  fi
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

# The topic names the daemon's code can create, read from the code itself: the bridge's
# constants (topics.hpp), the ROS 2 names of options.cpp (relative ones both without and with
# a namespace, absolute ones as they are), the sensors' default topics, and every sensor topic
# a shipped configuration or the documentation names (motion capture has no default).
code_topics() {
  local header="$source_dir/core/include/swivel/dds/topics.hpp"
  local options="$source_dir/core/dds/src/options.cpp" name
  sed -n 's/^inline constexpr const char\* k[A-Za-z]*Topic = "\(.*\)";$/\1/p' "$header"
  {
    sed -n 's/.*ros2_topic(ros_namespace, "\([a-z_/]*\)").*/\1/p' "$options"
    sed -n 's/.*parse_sensor_topic([a-z]*, ros_namespace, "\([a-z_/]*\)".*/\1/p' "$options"
    # topic: values in the shipped configurations (commented examples too) and the docs.
    sed -n 's/^[ #]*topic: *\([A-Za-z_/][A-Za-z0-9_/]*\).*/\1/p' "$source_dir"/config/*.yaml
    grep -ho 'topic: /[A-Za-z0-9_/]*' "$source_dir/README.md" "$source_dir"/docs/*.md | sed 's/^topic: //'
  } | sort -u | while read -r name; do
    if [[ $name == /* ]]; then
      echo "rt${name}"
    else
      echo "rt/$name"
      echo "rt/robot1/$name"
    fi
  done
  sed -n 's/.*return "\(rt\/[a-z_/]*\)";.*/\1/p' "$options"
}

# Every topic the daemon's code creates is in exactly one family, with the grants of the role
# table; and the daemon itself, under the profile, starts on the DDS section of every shipped
# configuration with the ROS 2 topics and both sensor inputs enabled.
case_permissions_cover_every_bridge_topic() {
  local -a topics
  mapfile -t topics < <(code_topics | sort -u)
  local topic
  for topic in swivel_robot_state swivel_velocity_command rt/odom rt/robot1/cmd_vel rt/tf rt/imu \
    rt/robot1/imu rt/vrpn_mocap/docent/pose; do
    # A here-string, not a pipe: grep -q leaves at its first match, and under pipefail the
    # printf it leaves writing to a closed pipe would fail the test now and then.
    grep -qx "$topic" <<<"$(printf '%s\n' "${topics[@]}")" ||
      fail "the topics read from the code lack $topic: the extraction is broken"
  done
  echo "ok: ${#topics[@]} topic names read from the code: ${topics[*]}"
  local daemon_grants client_grants observer_grants
  for topic in "${topics[@]}"; do
    daemon_grants=$(access "$daemon" "$topic")
    client_grants=$(access "$client" "$topic")
    observer_grants=$(access "$observer" "$topic")
    case "$daemon_grants/$client_grants/$observer_grants" in
      w/r/r) echo "ok: $topic is state (daemon writes; client and observer read)" ;;
      r/w/-) echo "ok: $topic is an input (client writes; daemon reads; observer nothing)" ;;
      *) fail "$topic: daemon '$daemon_grants', client '$client_grants', observer" \
        "'$observer_grants' fits neither the state nor the input family" ;;
    esac
  done
  # And the families are what the daemon's interface says they are.
  [[ $(access "$daemon" swivel_robot_state) == w ]] || fail "robot state is not state"
  [[ $(access "$daemon" swivel_velocity_command) == r ]] || fail "velocity is not a command"
  [[ $(access "$daemon" nonexistent_topic) == - ]] || fail "an unlisted topic is not denied"

  # The domains: the governance and every grant cover exactly what swiveld accepts secured.
  local range
  range=0-$(sed -n 's/^inline constexpr std::uint32_t kMaxSecureDomainId = \([0-9]*\);$/\1/p' \
    "$source_dir/core/include/swivel/dds/topics.hpp")
  [[ $range != 0- ]] || fail "no kMaxSecureDomainId found in topics.hpp"
  local doc
  for doc in "$profile/governance.xml" "$profile"/identities/*/permissions.xml; do
    [[ $(tr -d ' \n' <"$doc" | grep -o '<min>[0-9]*</min><max>[0-9]*</max>' |
      sed 's/<min>\([0-9]*\)<\/min><max>\([0-9]*\)<\/max>/\1-\2/' | sort -u) == "$range" ]] ||
      fail "$doc does not cover domains $range, what dds.domain_id may be with DDS Security"
  done
  echo "ok: the governance and every grant cover domains $range, what dds.domain_id may be with DDS Security"

  # The real daemon on each shipped configuration's dds: section, grafted onto the simulated
  # demo (the hardware does not change what DDS creates), on this case's domain.
  local swiveld=${SWIVEL_SWIVELD:?} domain=${SWIVEL_TEST_DOMAIN:?} shipped ns run=0
  local etc="$work/etc"
  mkdir -p "$etc"
  cp -r "$source_dir/config/robots" "$source_dir/config/dds" "$etc/"
  for shipped in "$source_dir"/config/*.yaml; do
    for ns in "" robot1; do
      run=$((run + 1))
      local yaml="$etc/run$run.yaml"
      {
        awk '/^dds:/ {exit} {print}' "$source_dir/config/swiveld.yaml" |
          sed -e 's/^  realtime: true /  realtime: false /' -e 's/^  source: script /  source: none /'
        awk '/^dds:/ {p = 1; print; next} /^[a-z]/ {p = 0} p' "$shipped" |
          sed -E -e "s/^  domain_id: [0-9]+/  domain_id: $domain/" -e '/^  ros2:/,$d'
        echo "  ros2:"
        echo "    enabled: true"
        [[ -z $ns ]] || echo "    namespace: $ns"
        # The shipped sensor sections (the commented motion-capture example uncommented);
        # a sensor the configuration has no section for gets its default or README topic.
        awk '/^  ros2:/ {p = 1; next} /^  [a-z]/ {p = 0} p' \
          <(awk '/^dds:/ {p = 1; next} /^[a-z]/ {p = 0} p' "$shipped") |
          sed -E -e 's/^    # (mocap_pose:)/    \1/' -e 's/^    #   (topic|rate_hz):/      \1:/' |
          awk '/^    (imu|mocap_pose):/ {p = 1; print; next} /^    [a-z#]/ {p = 0} p'
      } >"$yaml"
      grep -q '^    imu:' "$yaml" || printf '    imu:\n      topic: imu\n' >>"$yaml"
      grep -q '^    mocap_pose:' "$yaml" ||
        printf '    mocap_pose:\n      topic: /vrpn_mocap/docent/pose\n' >>"$yaml"
      local what
      what="swiveld on the dds: of $(basename "$shipped")${ns:+, namespace $ns}"
      # The child truncates the log: without the rm the loop below could read the last run's.
      rm -f "$work/robot.log"
      CYCLONEDDS_URI=$daemon "$swiveld" --config "$yaml" >"$work/robot.log" 2>&1 &
      robot_pid=$!
      local up=0
      for _ in $(seq 200); do
        grep -qs 'motion capture from' "$work/robot.log" && { up=1; break; }
        kill -0 "$robot_pid" 2>/dev/null || break
        sleep 0.1
      done
      if [[ $up != 1 ]]; then
        sed 's/^/    /' "$yaml" >&2
        tail -n 20 "$work/robot.log" >&2
        fail "$what did not start under the daemon's permissions"
      fi
      kill -TERM "$robot_pid"
      wait "$robot_pid" || { tail -n 20 "$work/robot.log" >&2; fail "$what exited with an error"; }
      robot_pid=""
      echo "ok: $what starts under the profile: $(grep -o 'DDS: robot.*' "$work/robot.log" | cut -c1-60)...; $(grep -o 'gyro from [^ ]*' "$work/robot.log"); $(grep -o 'motion capture from [^ ]*' "$work/robot.log")"
    done
  done

  # A domain the profile cannot cover is refused at the configuration check, with the reason;
  # the same configuration without DDS Security passes.
  sed -E 's/^  domain_id: [0-9]+/  domain_id: 231/' "$etc/run1.yaml" >"$etc/domain231.yaml"
  local got=0
  CYCLONEDDS_URI=$daemon "$swiveld" --config "$etc/domain231.yaml" --check >"$work/out" 2>&1 || got=$?
  sed 's/^/    /' "$work/out" | tail -n 3
  [[ $got != 0 ]] && grep -q 'dds.domain_id: expected a domain in \[0, 230\] with DDS Security' "$work/out" ||
    fail "swiveld --check accepts domain 231 under the profile (exit $got)"
  CYCLONEDDS_URI=$plain "$swiveld" --config "$etc/domain231.yaml" --check >"$work/out" 2>&1 ||
    { cat "$work/out" >&2; fail "swiveld --check refuses domain 231 without DDS Security"; }
  echo "ok: dds.domain_id 231 is refused with the profile, accepted without"
}

case_profile_scripts_are_idempotent() {
  local dir="$work/profile"
  # No service group: everything private to its owner (the service's access is the
  # installed_service case's).
  export SWIVEL_SERVICE_GROUP=
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

# The service as installed and as its unit runs it: a profile made by root with the documented
# command, the unit's environment plus the documented drop-in, the installed swiveld.yaml, and
# swiveld started as an unprivileged system user in the service group (the unit's User= and
# Group=). The user and its group are created for the case and removed after it, so the
# profile names them through SWIVEL_SERVICE_GROUP (default: swivel, the unit's). A participant
# without the profile, an identity from another CA and an observer then get only what they
# should: nothing, nothing, and the state without the right to command.
case_installed_service_as_service_user_refuses_strangers() {
  local unit=${SWIVEL_INSTALLED_UNIT:?} installed=${SWIVEL_INSTALLED_CONFIG:?}
  local swiveld=${SWIVEL_SWIVELD:?} swivelctl=${SWIVEL_SWIVELCTL:?}
  local dropin="$scripts/secure-dropin.conf" domain=${SWIVEL_TEST_DOMAIN:?}
  if [[ $(id -u) -ne 0 ]]; then
    echo "skipped: needs root to create the service user and a root-made profile"
    exit 77
  fi
  # The service's environment as systemd builds it: the unit's Environment= lines, then the
  # drop-in's; the last assignment of a variable wins.
  local uri
  uri=$(sed -n 's/^Environment=CYCLONEDDS_URI=//p' "$unit" "$dropin" | tail -n 1)
  [[ $uri == file:///etc/swivel/security/identities/swiveld/cyclonedds.xml ]] ||
    fail "unit + drop-in give CYCLONEDDS_URI='$uri', not the profile's daemon configuration"
  local user group
  user=$(sed -n 's/^User=//p' "$unit") group=$(sed -n 's/^Group=//p' "$unit")
  [[ $user == swivel && $group == swivel ]] || fail "the unit runs as $user:$group, not swivel:swivel"

  # The service user: a system user with its own group, like swivel.sysusers.conf's.
  service_user="swivel-test-$$"
  useradd --system --user-group --no-create-home --home-dir /nonexistent \
    --shell /usr/sbin/nologin "$service_user" || fail "cannot create the user $service_user"
  local uid gid
  uid=$(id -u "$service_user") gid=$(getent group "$service_user" | cut -d: -f3)
  as_service() {
    setpriv --reuid="$uid" --regid="$gid" --init-groups --no-new-privs -- "$@"
  }
  [[ $(as_service id -u) == "$uid" ]] || fail "setpriv did not drop to $service_user"

  # The profile as the README makes it, by root, in the installed layout's place.
  chmod 755 "$work"
  local etc="$work/etc/swivel" security="$work/etc/swivel/security"
  mkdir -p "$etc"
  export SWIVEL_SERVICE_GROUP=$service_user  # for every profile script below
  "$scripts/make_profile.sh" "$security" >/dev/null
  # Re-running is documented as safe: it must keep the access the service needs.
  "$scripts/make_profile.sh" "$security" >/dev/null
  local f want got
  for f in ca:750 ca/identity_ca.pem:640 ca/permissions_ca.pem:640 identities/swiveld:750 \
    identities/swiveld/key.pem:640 identities/swiveld/cyclonedds.xml:640; do
    want="${f#*:} root:$service_user"
    got=$(stat -c '%a %U:%G' "$security/${f%%:*}")
    [[ $got == "$want" ]] || fail "${f%%:*} is $got after a re-run, expected $want"
  done
  for f in ca/identity_ca_key.pem ca/permissions_ca_key.pem identities/swivelctl/key.pem; do
    [[ $(stat -c '%a %U' "$security/$f") == "600 root" ]] || fail "$f is not private to root"
    ! as_service test -r "$security/$f" || fail "the service user can read $f"
  done
  echo "ok: the profile made by root gives $service_user the daemon's files and nothing else"
  # An observer, added as the README documents.
  "$scripts/make_identity.sh" swivelobs "$security" >/dev/null
  "$scripts/make_permissions.sh" swivelobs observer "$security" >/dev/null
  "$scripts/render_config.sh" swivelobs "$security" >/dev/null
  local client_uri="file://$security/identities/swivelctl/cyclonedds.xml"
  local observer_uri="file://$security/identities/swivelobs/cyclonedds.xml"
  # An intruder: the client's name from another identity CA, with this profile's public
  # documents (governance, the client's signed permissions).
  local rogue_dir="$work/rogue"
  "$scripts/make_ca.sh" "$rogue_dir" >/dev/null
  "$scripts/make_identity.sh" swivelctl "$rogue_dir" >/dev/null
  cp "$security/ca/permissions_ca.pem" "$rogue_dir/ca/"
  cp "$security/governance.p7s" "$rogue_dir/"
  cp "$security/identities/swivelctl/permissions.p7s" "$rogue_dir/identities/swivelctl/"
  "$scripts/render_config.sh" swivelctl "$rogue_dir" >/dev/null
  local rogue_uri="file://$rogue_dir/identities/swivelctl/cyclonedds.xml"
  uri=${uri//\/etc\/swivel\/security/$security}  # the case's profile stands in for /etc's

  # The installed layout: swiveld.yaml with robots/ and dds/ beside it, on this case's domain.
  cp -r "$source_dir/config/robots" "$source_dir/config/dds" "$etc/"
  sed -e "s/^  domain_id: 0 /  domain_id: $domain /" -e 's/^  realtime: true /  realtime: false /' \
    "$installed" >"$etc/swiveld.yaml"
  grep -q '^  source: none ' "$etc/swiveld.yaml" ||
    fail "the installed configuration drives from a script at start-up"
  grep -q '^  config: dds/loopback.xml ' "$etc/swiveld.yaml" ||
    fail "the installed configuration no longer names dds.config: this case tests that conflict"
  grep -q "^  domain_id: $domain " "$etc/swiveld.yaml" || fail "could not move to domain $domain"

  # Without the service group (the scripts' fallback, and all they did before) the service
  # user cannot read the daemon's files; swiveld fails closed and its error says which and why.
  local private="$work/private"
  SWIVEL_SERVICE_GROUP='' "$scripts/make_profile.sh" "$private" >/dev/null
  local got=0
  as_service env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin \
    "CYCLONEDDS_URI=file://$private/identities/swiveld/cyclonedds.xml" \
    "SWIVEL_PLUGIN_PATH=${SWIVEL_PLUGIN_PATH:-}" \
    "$swiveld" --config "$etc/swiveld.yaml" >"$work/private.log" 2>&1 || got=$?
  grep 'swiveld error' "$work/private.log" | sed 's/^/    robot| /'
  [[ $got != 0 ]] || fail "swiveld started without access to its credentials"
  grep -qF "cannot read the DDS configuration $private/identities/swiveld/cyclonedds.xml (Permission denied, uid $uid)" \
    "$work/private.log" || fail "swiveld's error does not name the unreadable configuration"
  echo "ok: a profile private to root: swiveld as $service_user exits $got, naming the file it cannot read"

  # setpriv and env exec: the background job's pid is swiveld's.
  setpriv --reuid="$uid" --regid="$gid" --init-groups --no-new-privs -- \
    env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin "CYCLONEDDS_URI=$uri" \
    "SWIVEL_PLUGIN_PATH=${SWIVEL_PLUGIN_PATH:-}" \
    "$swiveld" --config "$etc/swiveld.yaml" >"$work/robot.log" 2>&1 &
  robot_pid=$!
  local up=0
  for _ in $(seq 200); do
    grep -qs 'DDS: robot' "$work/robot.log" && { up=1; break; }
    kill -0 "$robot_pid" 2>/dev/null || break
    sleep 0.1
  done
  [[ $up == 1 ]] || { cat "$work/robot.log" >&2; fail "swiveld did not start as $service_user"; }
  grep 'DDS: robot' "$work/robot.log"
  [[ $(readlink "/proc/$robot_pid/exe") == "$(readlink -f "$swiveld")" ]] ||
    fail "pid $robot_pid is not swiveld"
  [[ $(awk '/^Uid:/ {print $2 $3 $4 $5}' "/proc/$robot_pid/status") == "$uid$uid$uid$uid" &&
     $(awk '/^Gid:/ {print $2}' "/proc/$robot_pid/status") == "$gid" ]] ||
    fail "swiveld does not run as $service_user ($(grep -E '^(Uid|Gid):' "/proc/$robot_pid/status" | xargs))"
  grep -q "CYCLONEDDS_URI=$uri (environment; it overrides dds.config file://$etc/dds/loopback.xml)" \
    "$work/robot.log" || fail "swiveld's log does not say that the environment overrides dds.config"
  echo "ok: swiveld runs as $service_user (uid $uid) with the profile's daemon configuration"

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
  ctl "$client_uri" 0 "trusted client reads the pose" echo state --json --count 1 --timeout 15
  local before
  before=$(grep -o '"x_m":[^,]*' "$work/out" | head -n 1)
  ctl "$plain" 1 "participant without security reads nothing" echo state --count 1 --timeout 3
  ctl "$rogue_uri" 1 "identity from another CA reads nothing" echo state --count 1 --timeout 3
  ctl "$observer_uri" 0 "observer reads the pose" echo state --json --count 1 --timeout 15
  ctl "$observer_uri" 1 "observer may not command" drive 0.5 0 0 --for 1.5
  grep -q 'Not Allowed By Security' "$work/err" || fail "the observer's refusal does not name security"
  # Commands from strangers reach no reader: the robot stays where it is.
  CYCLONEDDS_URI=$plain "$swivelctl" drive 0.5 0 0 --for 1.5 --domain "$domain" \
    >"$work/out" 2>&1 || true
  CYCLONEDDS_URI=$rogue_uri "$swivelctl" drive 0.5 0 0 --for 1.5 --domain "$domain" \
    >"$work/out" 2>&1 || true
  ctl "$client_uri" 0 "trusted client reads the pose again" echo state --json --count 1 --timeout 15
  local after
  after=$(grep -o '"x_m":[^,]*' "$work/out" | head -n 1)
  [[ -n $before && $before == "$after" ]] ||
    fail "the robot moved on a stranger's command ($before -> $after)"
  echo "ok: the robot has not moved ($after)"
  kill -TERM "$robot_pid"
  wait "$robot_pid" || fail "swiveld exited with an error"
  robot_pid=""
}

# start_swiveld URI WHAT: the real daemon on the simulated demo (installed-like: no script,
# no real-time), this case's domain, with configuration URI; waits for its DDS line.
start_swiveld() {
  local uri=$1 what=$2 domain=${SWIVEL_TEST_DOMAIN:?}
  mkdir -p "$work/etc"
  cp -r "$source_dir/config/robots" "$source_dir/config/dds" "$work/etc/"
  sed -e "s/^  domain_id: 0 /  domain_id: $domain /" -e 's/^  realtime: true /  realtime: false /' \
    -e 's/^  source: script /  source: none /' "$source_dir/config/swiveld.yaml" \
    >"$work/etc/swiveld.yaml"
  rm -f "$work/robot.log"  # the child truncates it: the loop must not read the last run's
  CYCLONEDDS_URI=$uri "${SWIVEL_SWIVELD:?}" --config "$work/etc/swiveld.yaml" >"$work/robot.log" 2>&1 &
  robot_pid=$!
  for _ in $(seq 200); do
    grep -qs 'DDS: robot' "$work/robot.log" && return 0
    kill -0 "$robot_pid" 2>/dev/null || break
    sleep 0.1
  done
  cat "$work/robot.log" >&2
  fail "$what did not start"
}

stop_swiveld() {
  kill -TERM "$robot_pid"
  wait "$robot_pid" || { tail -n 20 "$work/robot.log" >&2; fail "swiveld exited with an error"; }
  robot_pid=""
}

# The daemon warns when its identity (whose validity its permissions share) nears its end,
# and not when it has a year to go.
case_daemon_warns_before_its_identity_expires() {
  local dir="$work/short"
  SWIVEL_SERVICE_GROUP='' SWIVEL_IDENTITY_DAYS=10 "$scripts/make_profile.sh" "$dir" >/dev/null
  start_swiveld "file://$dir/identities/swiveld/cyclonedds.xml" "swiveld with a 10-day identity"
  # A tool warns too, on stderr: its standard output stays its data.
  CYCLONEDDS_URI="file://$dir/identities/swivelctl/cyclonedds.xml" "${SWIVEL_SWIVELCTL:?}" \
    echo state --json --count 1 --timeout 15 --domain "${SWIVEL_TEST_DOMAIN:?}" \
    >"$work/out" 2>"$work/err" || { cat "$work/out" "$work/err" >&2; fail "swivelctl with a 10-day identity read no state"; }
  grep -q '^warning: DDS Security: the permissions .* in 9 days' "$work/err" ||
    { cat "$work/err" >&2; fail "swivelctl does not warn on stderr that its identity expires"; }
  [[ $(head -c 1 "$work/out") == "{" ]] && ! grep -q 'DDS Security' "$work/out" ||
    { cat "$work/out" >&2; fail "swivelctl's JSON output carries the warning"; }
  echo "ok: swivelctl with a 10-day identity warns on stderr; its JSON on stdout is clean"
  stop_swiveld
  grep 'DDS Security: the permissions' "$work/robot.log" | sed 's/^/    robot| /'
  grep -qE "warning: DDS Security: the permissions $dir/identities/swiveld/permissions.p7s .* expire on [0-9T:-]+ UTC, in 9 days" \
    "$work/robot.log" || fail "no warning that the 10-day identity expires in 9 days"
  echo "ok: a 10-day identity: the daemon warns it expires in 9 days"
  start_swiveld "$daemon" "swiveld with the fixture's 365-day identity"
  stop_swiveld
  if grep -q 'DDS Security: the permissions' "$work/robot.log"; then
    fail "the daemon warns about an identity valid for a year"
  fi
  echo "ok: a 365-day identity: no warning"
  # An identity already expired: the daemon refuses to start, and its own error says why.
  rm -rf "$dir/identities/swiveld"
  SWIVEL_SERVICE_GROUP='' SWIVEL_IDENTITY_DAYS=0 "$scripts/make_identity.sh" swiveld "$dir" >/dev/null
  SWIVEL_SERVICE_GROUP='' "$scripts/make_permissions.sh" swiveld daemon "$dir" >/dev/null
  SWIVEL_SERVICE_GROUP='' "$scripts/render_config.sh" swiveld "$dir"
  sleep 1.1  # past the certificate's notAfter, which is its notBefore
  local got=0
  CYCLONEDDS_URI="file://$dir/identities/swiveld/cyclonedds.xml" "${SWIVEL_SWIVELD:?}" \
    --config "$work/etc/swiveld.yaml" >"$work/robot.log" 2>&1 || got=$?
  grep 'swiveld error' "$work/robot.log" | sed 's/^/    robot| /'
  [[ $got != 0 ]] || fail "swiveld started with an expired identity"
  grep -qE 'swiveld error: dds_create_participant\(domain [0-9]+\): .*certificate has expired' \
    "$work/robot.log" || fail "swiveld's error does not say that its certificate expired"
  echo "ok: an expired identity: swiveld exits $got, its error names the expired certificate"
}

# A peer whose credentials fail the handshake retries for as long as it runs; the daemon
# logs at most one failure every 10 s, and the next line counts those it left out.
case_handshake_failures_are_rate_limited() {
  start_swiveld "$daemon" "swiveld under the profile"
  local got=0
  CYCLONEDDS_URI=$rogue "$peer" watch-none 13 >"$work/out" 2>"$work/rogue.err" || got=$?
  [[ $got == 0 ]] || { cat "$work/out" "$work/rogue.err" >&2; fail "the rogue peer exited $got"; }
  stop_swiveld
  local lines
  lines=$(grep -i 'handshake' "$work/robot.log" | grep -c 'failed' || true)
  grep -i 'handshake' "$work/robot.log" | sed 's/^/    robot| /'
  echo "    the rogue's own log (not rate-limited): $(grep -ic 'handshake.*failed' "$work/rogue.err" || true) handshake failures"
  [[ $lines -ge 1 ]] || fail "the daemon logged no handshake failure in 13 s of a rogue peer"
  [[ $lines -le 2 ]] || fail "the daemon logged $lines handshake failures in 13 s, at most 2 expected"
  if [[ $lines -eq 2 ]]; then
    grep -qE '\([0-9]+ more handshake failures since the last one logged, not logged: at most one every 10 s\)' \
      "$work/robot.log" || fail "the second handshake-failure line does not count the ones left out"
  fi
  echo "ok: $lines handshake-failure lines from the daemon in 13 s of a rogue peer"
}

"case_$case"
