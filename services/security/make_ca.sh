#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# shellcheck source-path=SCRIPTDIR
# Creates the identity CA and the permissions CA of a Swivel DDS Security profile.
# Usage: make_ca.sh [DIR]   (default ./swivel-security)
# Existing CAs are kept: replacing one would invalidate every identity and document it signed.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
source "$here/common.sh"

dir=$(profile_dir "${1:-}")
days=${SWIVEL_CA_DAYS:-3650}
mkdir -p "$dir/ca"
chmod 700 "$dir/ca"  # private until apply_access below opens what the service reads

make_ca() {
  local name=$1 subject=$2
  local key="$dir/ca/${name}_key.pem" cert="$dir/ca/${name}.pem"
  if [[ -f "$key" && -f "$cert" ]]; then
    return
  fi
  (umask 077 && openssl ecparam -name prime256v1 -genkey -noout -out "$key.tmp")
  mv "$key.tmp" "$key"
  openssl req -new -x509 -sha256 -key "$key" -out "$cert" -days "$days" -subj "$subject" \
    -addext "basicConstraints=critical,CA:TRUE" \
    -addext "keyUsage=critical,keyCertSign,cRLSign,digitalSignature"
  echo "created $cert"
}

make_ca identity_ca "/O=Swivel/CN=Swivel Identity CA"
make_ca permissions_ca "/O=Swivel/CN=Swivel Permissions CA"
apply_access "$dir"
