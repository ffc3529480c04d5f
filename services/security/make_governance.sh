#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# shellcheck source-path=SCRIPTDIR
# Renders the governance document from governance.xml.in and signs it with the permissions CA.
# Usage: make_governance.sh [DIR]   (default ./swivel-security)
# Environment: SWIVEL_RTPS_PROTECTION=SIGN|ENCRYPT (default SIGN: every RTPS message is
# authenticated; payloads and discovery are encrypted by the topic rule anyway).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
source "$here/common.sh"

dir=$(profile_dir "${1:-}")
require_ca "$dir"
rtps=${SWIVEL_RTPS_PROTECTION:-SIGN}
[[ "$rtps" == SIGN || "$rtps" == ENCRYPT ]] ||
  die "SWIVEL_RTPS_PROTECTION must be SIGN or ENCRYPT, not '$rtps'"

xml="$dir/governance.xml"
sed -e "s/@DOMAIN_MIN@/$SWIVEL_DOMAIN_MIN/g" -e "s/@DOMAIN_MAX@/$SWIVEL_DOMAIN_MAX/g" -e "s/@RTPS_PROTECTION@/$rtps/g" \
  "$here/governance.xml.in" >"$xml.tmp"
if cmp -s "$xml.tmp" "$xml" && signature_current "$dir" "$xml" "$dir/governance.p7s"; then
  rm -f "$xml.tmp"
  exit 0
fi
mv "$xml.tmp" "$xml"
sign_document "$dir" "$xml" "$dir/governance.p7s"
echo "created $dir/governance.p7s"
