#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# shellcheck source-path=SCRIPTDIR
# Writes the permissions document of identity NAME for ROLE and signs it with the
# permissions CA.
# Usage: make_permissions.sh NAME ROLE [DIR]   (default ./swivel-security)
#   ROLE daemon:   publishes state and diagnostics, subscribes to commands and sensor inputs
#   ROLE client:   subscribes to state and diagnostics, publishes commands and sensor inputs
#   ROLE observer: subscribes to state and diagnostics only
# The grant is valid exactly as long as NAME's certificate, so that re-running the script
# reproduces the same document and renewing the certificate renews the grant.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
source "$here/common.sh"
source "$here/topics.sh"

[[ $# -ge 2 ]] || die "usage: make_permissions.sh NAME daemon|client|observer [DIR]"
name=$1 role=$2
check_name "$name"
dir=$(profile_dir "${3:-}")
require_ca "$dir"
out="$dir/identities/$name"
[[ -f "$out/cert.pem" ]] || die "missing $out/cert.pem: run make_identity.sh $name $dir first"

case "$role" in
  daemon) publish=$SWIVEL_STATE_TOPICS subscribe=$SWIVEL_INPUT_TOPICS ;;
  client) publish=$SWIVEL_INPUT_TOPICS subscribe=$SWIVEL_STATE_TOPICS ;;
  observer) publish="" subscribe=$SWIVEL_STATE_TOPICS ;;
  *) die "role must be daemon, client or observer, not '$role'" ;;
esac

iso_date() { date -u -d "$1" +%Y-%m-%dT%H:%M:%S; }
not_before=$(iso_date "$(openssl x509 -in "$out/cert.pem" -noout -startdate | cut -d= -f2)")
not_after=$(iso_date "$(openssl x509 -in "$out/cert.pem" -noout -enddate | cut -d= -f2)")

topic_list() {
  local pattern
  echo "          <topics>"
  # Word splitting is the point: the lists are space-separated patterns. Globbing is off
  # so that a pattern is never expanded against the working directory.
  set -f
  for pattern in $1; do
    echo "            <topic>$pattern</topic>"
  done
  set +f
  echo "          </topics>"
}

rule() {
  local kind=$1 topics=$2
  [[ -n "$topics" ]] || return 0
  echo "        <$kind>"
  topic_list "$topics"
  echo "        </$kind>"
}

xml="$out/permissions.xml"
{
  cat <<XML
<?xml version="1.0" encoding="UTF-8"?>
<!-- Swivel permissions for CN=$name, role $role; written by make_permissions.sh. -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="${name}_${role}">
      <subject_name>CN=$name</subject_name>
      <validity>
        <not_before>$not_before</not_before>
        <not_after>$not_after</not_after>
      </validity>
      <allow_rule>
        <domains>
          <id_range>
            <min>$SWIVEL_DOMAIN_MIN</min>
            <max>$SWIVEL_DOMAIN_MAX</max>
          </id_range>
        </domains>
XML
  rule publish "$publish"
  rule subscribe "$subscribe"
  cat <<XML
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
XML
} >"$xml.tmp"

if cmp -s "$xml.tmp" "$xml" && signature_current "$dir" "$xml" "$out/permissions.p7s"; then
  rm -f "$xml.tmp"
  apply_access "$dir"
  exit 0
fi
mv "$xml.tmp" "$xml"
sign_document "$dir" "$xml" "$out/permissions.p7s"
apply_access "$dir"
echo "created $out/permissions.p7s ($role)"
