#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# CTest fixture: a fresh profile for the security cases.
#   DIR                    daemon swiveld, client swivelctl, observer swivelobs
#   DIR/rogue              an intruder: identity CN=swivelctl from another identity CA, with
#                          the genuine governance and the genuine client's signed permissions
#                          (public documents), so only its identity CA differs
# Usage: make_test_profiles.sh DIR   (needs SWIVEL_SECURITY_SCRIPTS)
set -euo pipefail
dir=$1
scripts=${SWIVEL_SECURITY_SCRIPTS:?}

rm -rf "$dir"
"$scripts/make_profile.sh" "$dir"
"$scripts/make_identity.sh" swivelobs "$dir"
"$scripts/make_permissions.sh" swivelobs observer "$dir"
"$scripts/render_config.sh" swivelobs "$dir"

rogue="$dir/rogue"
"$scripts/make_ca.sh" "$rogue"
"$scripts/make_identity.sh" swivelctl "$rogue"
cp "$dir/ca/permissions_ca.pem" "$rogue/ca/permissions_ca.pem"
cp "$dir/governance.p7s" "$rogue/governance.p7s"
cp "$dir/identities/swivelctl/permissions.p7s" "$rogue/identities/swivelctl/permissions.p7s"
"$scripts/render_config.sh" swivelctl "$rogue"

# The rogue certificate must really come from another CA, or the isolation case proves nothing.
if openssl verify -CAfile "$dir/ca/identity_ca.pem" "$rogue/identities/swivelctl/cert.pem" \
  >/dev/null 2>&1; then
  echo "rogue identity unexpectedly verifies against the genuine identity CA" >&2
  exit 1
fi
