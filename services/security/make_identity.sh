#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# shellcheck source-path=SCRIPTDIR
# Creates the private key and the certificate (subject CN=NAME, signed by the identity CA)
# of one participant.
# Usage: make_identity.sh NAME [DIR]   (default ./swivel-security)
# An identity whose certificate still verifies against the CA is kept.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
source "$here/common.sh"

[[ $# -ge 1 ]] || die "usage: make_identity.sh NAME [DIR]"
name=$1
check_name "$name"
dir=$(profile_dir "${2:-}")
require_ca "$dir"
days=${SWIVEL_IDENTITY_DAYS:-365}

out="$dir/identities/$name"
mkdir -p "$out"
chmod 700 "$out"  # private until apply_access opens the daemon's to the service group
key="$out/key.pem" cert="$out/cert.pem"

if [[ -f "$key" && -f "$cert" ]] &&
  openssl verify -CAfile "$dir/ca/identity_ca.pem" "$cert" >/dev/null 2>&1; then
  apply_access "$dir"
  exit 0
fi

(umask 077 && openssl ecparam -name prime256v1 -genkey -noout -out "$key.tmp")
mv "$key.tmp" "$key"
csr=$(mktemp)
ext=$(mktemp)
trap 'rm -f "$csr" "$ext"' EXIT
openssl req -new -sha256 -key "$key" -subj "/CN=$name" -out "$csr"
printf '%s\n' "basicConstraints=critical,CA:FALSE" \
  "keyUsage=critical,digitalSignature,keyAgreement" >"$ext"
openssl x509 -req -sha256 -in "$csr" -days "$days" -extfile "$ext" \
  -CA "$dir/ca/identity_ca.pem" -CAkey "$dir/ca/identity_ca_key.pem" -CAcreateserial \
  -CAserial "$dir/ca/identity_ca.srl" -out "$cert" 2>/dev/null
apply_access "$dir"
echo "created $cert"
