#!/usr/bin/env bash
# ctest node.mcap_core_reads_recording: records a short live session to MCAP
# with teleop_record (teleop_server + teleop_master, loopback, this test's domain), then reads
# the file with @mcap/core and decodes every message with its IDL schema (mcap_check.mjs).
#
#   run_mcap_check.sh BUILD_DIR DOMAIN
#
# DOMAIN: kNodeMcapCheck of tests/support/domains.hpp. Skipped (exit 77) only when node is not
# installed; the npm packages come from `npm ci` in tests/node (deploy/build.sh runs it).
set -u
build="$1"
domain="$2"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# shellcheck source=require_node.sh
. "$here/require_node.sh"
require_node "$here" @mcap/core
export TELEOP_PROFILE=loopback
unset TELEOP_DOMAIN
tmp="$(mktemp -d)"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
  wait 2>/dev/null
  rm -rf "$tmp"
}
trap cleanup EXIT
file="$tmp/session.mcap"
"$build/client/teleop_record" --domain "$domain" --out "$file" >"$tmp/record.log" 2>&1 &
rec=$!
pids+=("$rec")
for _ in $(seq 100); do grep -q "recording" "$tmp/record.log" && break; sleep 0.1; done
"$build/server/teleop_server" --domain "$domain" --duration 60 --quiet >"$tmp/server.log" 2>&1 &
server=$!
pids+=("$server")
if ! timeout 60 "$build/client/teleop_master" --domain "$domain" --duration 2 --homing 0.5 \
  --quiet >"$tmp/master.log" 2>&1; then
  echo "FAILED: the session's master did not finish"
  tail -5 "$tmp/master.log"
  exit 1
fi
kill -TERM "$server"
wait "$server"
sleep 0.2
kill -INT "$rec"
if ! wait "$rec"; then
  echo "FAILED: teleop_record"
  cat "$tmp/record.log"
  exit 1
fi
cat "$tmp/record.log"
node "$here/mcap_check.mjs" "$file"
