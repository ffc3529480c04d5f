#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# shellcheck source-path=SCRIPTDIR
# Creates a complete profile: both CAs, the signed governance, the daemon's identity and one
# trusted client's, each with signed permissions and a rendered Cyclone configuration.
# Usage: make_profile.sh [DIR]   (default ./swivel-security)
# Environment: SWIVEL_DAEMON_IDENTITY (default swiveld), SWIVEL_CLIENT_IDENTITY (default
# swivelctl). Safe to re-run: what exists and still verifies is kept.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
source "$here/common.sh"

dir=$(profile_dir "${1:-}")
daemon=${SWIVEL_DAEMON_IDENTITY:-swiveld}
client=${SWIVEL_CLIENT_IDENTITY:-swivelctl}

"$here/make_ca.sh" "$dir"
"$here/make_governance.sh" "$dir"
for pair in "$daemon:daemon" "$client:client"; do
  name=${pair%%:*} role=${pair#*:}
  "$here/make_identity.sh" "$name" "$dir"
  "$here/make_permissions.sh" "$name" "$role" "$dir"
  "$here/render_config.sh" "$name" "$dir"
done
echo "profile ready in $dir"
echo "  daemon: CYCLONEDDS_URI=file://$dir/identities/$daemon/cyclonedds.xml"
echo "  client: CYCLONEDDS_URI=file://$dir/identities/$client/cyclonedds.xml"
