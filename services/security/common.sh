# SPDX-License-Identifier: Apache-2.0
# shellcheck shell=bash
# Sourced by the profile scripts: the profile's layout and the helpers they share.

# Layout of a profile directory:
#   ca/identity_ca.pem, ca/identity_ca_key.pem        trusts participants' identities
#   ca/permissions_ca.pem, ca/permissions_ca_key.pem  signs governance and permissions
#   governance.xml, governance.p7s                    domain-wide protection rules
#   identities/NAME/{cert.pem,key.pem}                one participant's identity
#   identities/NAME/permissions.{xml,p7s}             what NAME may publish and subscribe
#   identities/NAME/cyclonedds.xml                    the configuration NAME runs with
#
# Access: the daemon runs as the service user (the unit's User=swivel, Group=swivel), so what
# it reads is group-readable by the service group when that group exists: ca/ and the daemon's
# identity folder 0750, the CA certificates and the daemon's files 0640. The CA keys and every
# other identity stay private to the owner (0600 files in 0700 folders). Every script applies
# this after its work, so running any of them again restores it.

# The DDS domains the governance and every grant cover: all that DDS Security can name (its
# DomainId is 0..230; Cyclone refuses a document with more). swiveld refuses a dds.domain_id
# above 230 with a configuration that enables DDS Security (kMaxSecureDomainId in
# core/include/swivel/dds/topics.hpp), so no domain it runs secured on falls outside these.
# shellcheck disable=SC2034  # read by the scripts that source this file
SWIVEL_DOMAIN_MIN=0
# shellcheck disable=SC2034
SWIVEL_DOMAIN_MAX=230

# The daemon's identity (the one the service reads) and the group it runs as.
daemon_identity() { echo "${SWIVEL_DAEMON_IDENTITY:-swiveld}"; }
service_group() { echo "${SWIVEL_SERVICE_GROUP-swivel}"; }  # set empty: no group

die() {
  echo "$(basename "$0"): $*" >&2
  exit 1
}

profile_dir() {
  local dir=${1:-./swivel-security}
  mkdir -p "$dir"
  # Absolute, so that the rendered configuration works from any working directory.
  (cd "$dir" && pwd)
}

check_name() {
  # The name becomes a certificate subject, a path component and XML text: keep it plain.
  [[ "$1" =~ ^[A-Za-z0-9][A-Za-z0-9._-]*$ ]] ||
    die "identity name '$1' must match [A-Za-z0-9][A-Za-z0-9._-]*"
}

require_ca() {
  local dir=$1
  for f in identity_ca.pem identity_ca_key.pem permissions_ca.pem permissions_ca_key.pem; do
    [[ -f "$dir/ca/$f" ]] || die "missing $dir/ca/$f: run make_ca.sh $dir first"
  done
}

# S/MIME-sign a document with the permissions CA, the format DDS Security expects.
sign_document() {
  local dir=$1 in=$2 out=$3
  openssl smime -sign -text -in "$in" -out "$out.tmp" \
    -signer "$dir/ca/permissions_ca.pem" -inkey "$dir/ca/permissions_ca_key.pem"
  mv "$out.tmp" "$out"
}

# True when a signed document verifies against the permissions CA and matches its source.
signature_current() {
  local dir=$1 in=$2 signed=$3
  [[ -f "$in" && -f "$signed" ]] || return 1
  openssl smime -verify -text -in "$signed" -CAfile "$dir/ca/permissions_ca.pem" \
    -out /dev/stdout 2>/dev/null | tr -d '\r' | cmp -s - "$in"
}

# True when the service group exists and this user may give files to it (root, or a member).
service_group_usable() {
  local group
  group=$(service_group)
  [[ -n "$group" ]] && getent group "$group" >/dev/null || return 1
  [[ $(id -u) -eq 0 ]] || grep -qx "$group" <<<"$(id -nG | tr ' ' '\n')"
}

# shared PATH MODE: PATH group-owned by the service group with MODE (0750 or 0640) when the
# group is usable, otherwise private to the owner (0700 or 0600).
shared() {
  local path=$1 mode=$2
  if service_group_usable; then
    chgrp "$(service_group)" "$path"
    chmod "$mode" "$path"
  elif [[ -d "$path" ]]; then
    chmod 700 "$path"
  else
    chmod 600 "$path"
  fi
}

# Applies the access rules above to the profile in DIR (whatever of it exists).
apply_access() {
  local dir=$1 daemon f d
  daemon=$(daemon_identity)
  if [[ -d "$dir/ca" ]]; then
    shared "$dir/ca" 750
    for f in "$dir"/ca/*; do
      [[ -f "$f" ]] || continue
      case "$f" in
        *_ca.pem) shared "$f" 640 ;;
        *) chmod 600 "$f" ;;  # the CA keys and the serial stay the owner's
      esac
    done
  fi
  for d in "$dir"/identities/*/; do
    [[ -d "$d" ]] || continue
    d=${d%/}
    if [[ $(basename "$d") == "$daemon" ]]; then
      shared "$d" 750
      for f in "$d"/*; do [[ -f "$f" ]] && shared "$f" 640; done
    else
      chmod 700 "$d"
      for f in "$d"/*; do [[ -f "$f" ]] && chmod 600 "$f"; done
    fi
  done
  return 0
}
