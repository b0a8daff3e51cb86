#!/usr/bin/env bash
# Makes the files of the DDS Security profiles (secure, secure_lan, ...; docs/networking.md,
# "Security") with openssl: a test identity CA and permissions CA, an identity certificate and
# key per participant, the governance document and one permissions document per participant,
# both S/MIME-signed by the permissions CA (as the DDS Security spec requires).
#
#   deploy/make_security.sh [options] DIR
#
#   --identity NAME:ROLE   an identity to make (repeatable); ROLE is server, master, operator,
#                          observer or bench (teleop_bench rtt's bench/* topics only).
#                          Default: server:server master:master operator:operator observer:observer
#   --days N               validity of certificates and permissions (default 365)
#   --hours N              short-lived identities instead: each identity's certificate and
#                          permissions valid for N hours, 1-8760, from 5 minutes before now (the
#                          CAs keep --days). Every host's clock must be within those 5 minutes
#                          (NTP/chrony, docs/networking.md "Time"); renew before they expire
#   --org NAME             O= of every subject (default teleop-test)
#   --domains MIN-MAX      domain ids governance and permissions cover (default 0-232)
#   --no-other             do not make DIR/other (a foreign CA with identity "nobody")
#
# Layout (what --security-dir DIR and --identity NAME read):
#   DIR/identity_ca.cert.pem       trust anchor of authentication (shared by all)
#   DIR/permissions_ca.cert.pem    trust anchor of governance and permissions (shared by all)
#   DIR/governance.p7s             signed governance (governance.xml: the unsigned text)
#   DIR/NAME/identity.cert.pem     NAME's certificate, signed by the identity CA
#   DIR/NAME/identity.key.pem      NAME's private key (give it to NAME's host only)
#   DIR/NAME/permissions.p7s       NAME's signed permissions (permissions.xml: unsigned text)
#   DIR/ca/*.key.pem               the CAs' private keys: keep them off the participants' hosts
#   DIR/other/                     the same layout with another CA and one identity, "nobody":
#                                  valid files that our participants must not trust (tests)
# Running again with an existing DIR/ca reuses the CAs and adds or renews the identities given.
#
# Roles (permissions; default DENY for everything not listed):
#   server    publishes teleop/slave_state, scene, mesh_topology, mesh_frame, events,
#             server_stats and the observers' copies slave_state_view, slave_state_monitor,
#             mesh_frame_monitor; subscribes teleop/*
#   master    publishes teleop/master_command, master_state, events, tuning_status, experiment,
#             device_command (to an external device driver) and the observers' copies
#             master_state_view, master_state_monitor; subscribes teleop/*
#   operator  a device driver or a tuning tool (teleop_viewer --drive): publishes
#             teleop/device_state and teleop/tuning; subscribes teleop/*
#   observer  subscribes teleop/*; publishes nothing
#   bench     publishes and subscribes bench/* (teleop_bench rtt); no teleop topic
# Keys are ECDSA P-256 (prime256v1), signatures SHA-256: both supported by Fast DDS 2.9's
# builtin.PKI-DH. A run takes under a second of CPU (about 10 s of wall time on the loaded
# 2-core test machine).
set -euo pipefail

usage() { sed -n '2,43p' "$0" | sed 's/^# \{0,1\}//'; }
die() {
  echo "make_security.sh: $*" >&2
  exit 2
}

days=365
hours=""
org="teleop-test"
domains="0-232"
other=1
identities=()
dir=""
while [ $# -gt 0 ]; do
  case "$1" in
    --identity) [ $# -ge 2 ] || die "--identity needs NAME:ROLE"; identities+=("$2"); shift 2 ;;
    --days) [ $# -ge 2 ] || die "--days needs a number"; days="$2"; shift 2 ;;
    --hours) [ $# -ge 2 ] || die "--hours needs a number"; hours="$2"; shift 2 ;;
    --org) [ $# -ge 2 ] || die "--org needs a name"; org="$2"; shift 2 ;;
    --domains) [ $# -ge 2 ] || die "--domains needs MIN-MAX"; domains="$2"; shift 2 ;;
    --no-other) other=0; shift ;;
    -h | --help) usage; exit 0 ;;
    -*) die "unknown option '$1' (see --help)" ;;
    *) [ -z "$dir" ] || die "one DIR only (got '$dir' and '$1')"; dir="$1"; shift ;;
  esac
done
[ -n "$dir" ] || die "missing DIR (see --help)"
command -v openssl >/dev/null 2>&1 || die "openssl not found (Debian package openssl; deploy/setup.sh installs it)"
[[ "$days" =~ ^[0-9]+$ ]] && [ "$days" -ge 1 ] && [ "$days" -le 36500 ] ||
  die "--days '$days' is not an integer in [1, 36500]"
[ -z "$hours" ] || { [[ "$hours" =~ ^[0-9]+$ ]] && [ "$hours" -ge 1 ] && [ "$hours" -le 8760 ]; } ||
  die "--hours '$hours' is not an integer in [1, 8760]"
[[ "$org" =~ ^[A-Za-z0-9\ ._-]+$ ]] || die "--org '$org': use letters, digits, space . _ - only"
[[ "$domains" =~ ^([0-9]+)-([0-9]+)$ ]] || die "--domains '$domains' is not MIN-MAX"
dmin="${BASH_REMATCH[1]}"
dmax="${BASH_REMATCH[2]}"
[ "$dmin" -le "$dmax" ] && [ "$dmax" -le 232 ] || die "--domains '$domains': need 0 <= MIN <= MAX <= 232"
[ ${#identities[@]} -gt 0 ] || identities=(server:server master:master operator:operator observer:observer)
for spec in "${identities[@]}"; do
  [[ "$spec" =~ ^[A-Za-z0-9_.-]+:(server|master|operator|observer|bench)$ ]] ||
    die "--identity '$spec' is not NAME:ROLE (NAME of letters, digits, _ . -; ROLE server, master, operator, observer or bench)"
  [[ "$spec" != ca:* && "$spec" != other:* ]] || die "--identity '$spec': names 'ca' and 'other' are reserved"
done

umask 077
mkdir -p "$dir"
dir="$(cd "$dir" && pwd)"

# openssl writes progress to stderr; keep it quiet unless something fails
ossl() {
  local out
  if ! out="$(openssl "$@" 2>&1)"; then
    echo "make_security.sh: openssl $1 failed:" >&2
    echo "$out" >&2
    exit 1
  fi
}

# validity of the identities (certificates and permissions), as date(1) expressions
if [ -n "$hours" ]; then
  valid_from="$(date -u -d "now - 5 minutes" '+%Y-%m-%d %H:%M:%S UTC')"
  valid_until="$(date -u -d "now + $hours hours" '+%Y-%m-%d %H:%M:%S UTC')"
else
  valid_from="$(date -u -d "now - 1 day" '+%Y-%m-%d %H:%M:%S UTC')"
  valid_until="$(date -u -d "now + $days days" '+%Y-%m-%d %H:%M:%S UTC')"
fi

# utc time in the form of the permissions document (xs:dateTime)
iso() { date -u -d "$1" +%Y-%m-%dT%H:%M:%S; }

# make_ca DIR KEYDIR NAME CN: a self-signed CA certificate DIR/NAME.cert.pem, key KEYDIR/NAME.key.pem
make_ca() {
  local d="$1" kd="$2" name="$3" cn="$4"
  mkdir -p "$kd"
  if [ -f "$kd/$name.key.pem" ] && [ -f "$d/$name.cert.pem" ]; then return; fi
  ossl ecparam -name prime256v1 -genkey -noout -out "$kd/$name.key.pem"
  ossl req -new -x509 -sha256 -days "$days" -key "$kd/$name.key.pem" -out "$d/$name.cert.pem" \
    -subj "/C=XX/O=$org/CN=$cn" \
    -addext "basicConstraints=critical,CA:TRUE" -addext "keyUsage=critical,keyCertSign,cRLSign,digitalSignature"
}

governance_xml() {
  cat <<EOF
<?xml version="1.0" encoding="UTF-8"?>
<!-- teleop governance: every participant must authenticate (PKI-DH) and hold permissions
     (join access control); RTPS messages, discovery, liveliness and every teleop topic's data
     are encrypted (AES-GCM); read and write access control on every topic. -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains>
        <id_range><min>$dmin</min><max>$dmax</max></id_range>
      </domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>ENCRYPT</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>NONE</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
EOF
}

# topics each role may publish (subscribing: teleop/* for every role)
publish_topics() {
  case "$1" in
    server) echo "teleop/slave_state teleop/scene teleop/mesh_topology teleop/mesh_frame teleop/events teleop/server_stats teleop/slave_state_view teleop/slave_state_monitor teleop/mesh_frame_monitor" ;;
    master) echo "teleop/master_command teleop/master_state teleop/events teleop/tuning_status teleop/experiment teleop/device_command teleop/master_state_view teleop/master_state_monitor" ;;
    operator) echo "teleop/device_state teleop/tuning" ;;
    observer) echo "" ;;
    bench) echo "bench/*" ;;
  esac
}

# permissions_xml NAME ROLE SUBJECT
permissions_xml() {
  local name="$1" role="$2" subject="$3" pub t sub="teleop/*"
  pub="$(publish_topics "$role")"
  [ "$role" = bench ] && sub="bench/*"
  cat <<EOF
<?xml version="1.0" encoding="UTF-8"?>
<!-- teleop permissions of '$name' (role $role) -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="teleop_${name}">
      <subject_name>$subject</subject_name>
      <validity>
        <not_before>$(iso "$valid_from")</not_before>
        <not_after>$(iso "$valid_until")</not_after>
      </validity>
      <allow_rule>
        <domains>
          <id_range><min>$dmin</min><max>$dmax</max></id_range>
        </domains>
EOF
  if [ -n "$pub" ]; then
    echo "        <publish>"
    echo "          <topics>"
    for t in $pub; do echo "            <topic>$t</topic>"; done
    echo "          </topics>"
    echo "        </publish>"
  fi
  cat <<EOF
        <subscribe>
          <topics>
            <topic>$sub</topic>
          </topics>
        </subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
EOF
}

# sign_smime IN OUT D KD: S/MIME-sign IN with the permissions CA of D (key in KD)
sign_smime() {
  ossl smime -sign -text -in "$1" -out "$2" -signer "$3/permissions_ca.cert.pem" \
    -inkey "$4/permissions_ca.key.pem"
}

# sign_short_lived CSR CERT EXT D KD: CSR signed by the identity CA of D (key in KD), valid
# from $valid_from to $valid_until (openssl ca: x509 -req counts whole days only)
sign_short_lived() {
  local csr="$1" cert="$2" ext="$3" d="$4" kd="$5" work
  work="$(mktemp -d)"
  [ -f "$kd/identity_ca.srl" ] || openssl rand -hex 16 >"$kd/identity_ca.srl"
  : >"$work/index.txt"
  cat >"$work/ca.cnf" <<EOF
[ ca ]
default_ca = teleop
[ teleop ]
database = $work/index.txt
new_certs_dir = $work
serial = $kd/identity_ca.srl
default_md = sha256
policy = any
unique_subject = no
[ any ]
countryName = optional
organizationName = optional
organizationalUnitName = optional
commonName = supplied
EOF
  ossl ca -batch -config "$work/ca.cnf" -cert "$d/identity_ca.cert.pem" \
    -keyfile "$kd/identity_ca.key.pem" -in "$csr" -out "$cert" -notext -extfile "$ext" \
    -startdate "$(date -u -d "$valid_from" +%Y%m%d%H%M%SZ)" \
    -enddate "$(date -u -d "$valid_until" +%Y%m%d%H%M%SZ)"
  rm -rf "$work"
}

# make_identity D KD NAME ROLE
make_identity() {
  local d="$1" kd="$2" name="$3" role="$4" subject
  local id="$d/$name"
  mkdir -p "$id"
  ossl ecparam -name prime256v1 -genkey -noout -out "$id/identity.key.pem"
  ossl req -new -sha256 -key "$id/identity.key.pem" -out "$id/identity.csr.pem" \
    -subj "/C=XX/O=$org/OU=$role/CN=$name"
  local ext="$id/identity.ext"
  printf 'basicConstraints=critical,CA:FALSE\nkeyUsage=critical,digitalSignature,keyAgreement\n' >"$ext"
  if [ -n "$hours" ]; then
    sign_short_lived "$id/identity.csr.pem" "$id/identity.cert.pem" "$ext" "$d" "$kd"
  else
    ossl x509 -req -sha256 -days "$days" -in "$id/identity.csr.pem" -CA "$d/identity_ca.cert.pem" \
      -CAkey "$kd/identity_ca.key.pem" -CAcreateserial -CAserial "$kd/identity_ca.srl" \
      -extfile "$ext" -out "$id/identity.cert.pem"
  fi
  rm -f "$id/identity.csr.pem" "$ext"
  # the subject exactly as the certificate holds it (RFC 2253), as Fast DDS compares it
  subject="$(openssl x509 -in "$id/identity.cert.pem" -noout -subject -nameopt RFC2253)"
  subject="${subject#subject=}"
  permissions_xml "$name" "$role" "$subject" >"$id/permissions.xml"
  sign_smime "$id/permissions.xml" "$id/permissions.p7s" "$d" "$kd"
  chmod 600 "$id/identity.key.pem"
  chmod 644 "$id/identity.cert.pem" "$id/permissions.xml" "$id/permissions.p7s"
}

# make_tree D KD LABEL IDENTITY...: CAs (reused if present), governance, identities
make_tree() {
  local d="$1" kd="$2" label="$3"
  shift 3
  mkdir -p "$d"
  make_ca "$d" "$kd" identity_ca "$label identity CA"
  make_ca "$d" "$kd" permissions_ca "$label permissions CA"
  governance_xml >"$d/governance.xml"
  sign_smime "$d/governance.xml" "$d/governance.p7s" "$d" "$kd"
  chmod 644 "$d/identity_ca.cert.pem" "$d/permissions_ca.cert.pem" "$d/governance.xml" \
    "$d/governance.p7s"
  local spec
  for spec in "$@"; do make_identity "$d" "$kd" "${spec%%:*}" "${spec##*:}"; done
}

chmod 755 "$dir"
make_tree "$dir" "$dir/ca" "teleop" "${identities[@]}"
if [ "$other" = 1 ]; then
  make_tree "$dir/other" "$dir/other/ca" "foreign" nobody:master
  chmod 755 "$dir/other"
fi
echo "make_security.sh: wrote $dir (identities: ${identities[*]}$([ "$other" = 1 ] && echo "; other/nobody"))"
