#!/usr/bin/env bash
# ctest node.ws_protocol_reads_bridge: a short live session (teleop_server +
# teleop_master, loopback, this test's domain) served by teleop_bridge on a port the system
# picks, read by @foxglove/ws-protocol's client with every message decoded from its omgidl
# schema (bridge_check.mjs).
#
#   run_bridge_check.sh BUILD_DIR DOMAIN
#
# DOMAIN: kNodeBridgeCheck of tests/support/domains.hpp. Skipped (exit 77) only when node is not
# installed; the npm packages come from `npm ci` in tests/node (deploy/build.sh runs it).
set -u
build="$1"
domain="$2"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# shellcheck source=require_node.sh
. "$here/require_node.sh"
require_node "$here" @foxglove/ws-protocol
# shellcheck source=session_lib.sh
. "$here/session_lib.sh"
node_websocket_flags
session_tmp
start_server_and_bridge "$build" "$domain"
timeout 60 "$build/client/teleop_master" --domain "$domain" --duration 8 --homing 0.5 \
  --quiet >"$tmp/master.log" 2>&1 &
pids+=("$!")
sleep 1
node "${node_flags[@]}" "$here/bridge_check.mjs" "ws://127.0.0.1:$port" 5
status=$?
kill -INT "$bridge"
wait "$bridge"
cat "$tmp/bridge.log"
exit "$status"
