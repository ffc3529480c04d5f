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
