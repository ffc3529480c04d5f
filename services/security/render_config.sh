#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# shellcheck source-path=SCRIPTDIR
# Renders secure.xml.in into DIR/identities/NAME/cyclonedds.xml, the configuration that
# identity NAME runs with: CYCLONEDDS_URI=file://DIR/identities/NAME/cyclonedds.xml
# Usage: render_config.sh NAME [DIR]   (default ./swivel-security)
# Environment: SWIVEL_DDS_SECURITY_PLUGIN_DIR, the folder holding libdds_security_*.so, only
# for a Cyclone DDS that cannot find its plugins by name. Debian's can: it looks the default
# names up on the library path and then in /usr/lib/<multiarch>/libddsc0debian/.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
source "$here/common.sh"

[[ $# -ge 1 ]] || die "usage: render_config.sh NAME [DIR]"
name=$1
check_name "$name"
dir=$(profile_dir "${2:-}")
out="$dir/identities/$name"
for f in cert.pem key.pem permissions.p7s; do
  [[ -f "$out/$f" ]] || die "missing $out/$f: create the identity and its permissions first"
done
[[ -f "$dir/governance.p7s" ]] || die "missing $dir/governance.p7s: run make_governance.sh"

plugin() {
  if [[ -n "${SWIVEL_DDS_SECURITY_PLUGIN_DIR:-}" ]]; then
    echo "${SWIVEL_DDS_SECURITY_PLUGIN_DIR%/}/libdds_security_$1.so"
  else
    echo "dds_security_$1"
  fi
}
# '|' delimits sed's expressions: paths contain '/', and check_name keeps '|' out of names.
sed -e "s|@NAME@|$name|g" -e "s|@PROFILE_DIR@|$dir|g" -e "s|@IDENTITY_DIR@|$out|g" \
  -e "s|@AUTH_LIBRARY@|$(plugin auth)|g" -e "s|@AC_LIBRARY@|$(plugin ac)|g" \
  -e "s|@CRYPTO_LIBRARY@|$(plugin crypto)|g" "$here/secure.xml.in" >"$out/cyclonedds.xml.tmp"
mv "$out/cyclonedds.xml.tmp" "$out/cyclonedds.xml"
apply_access "$dir"
