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
# Node 22 has a WebSocket client built in; Node 20.10+ behind a flag
node_flags=()
if ! node -e 'process.exit(typeof WebSocket === "function" ? 0 : 1)' 2>/dev/null; then
  node_flags=(--experimental-websocket)
fi
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
"$build/server/teleop_server" --domain "$domain" --duration 60 --quiet >"$tmp/server.log" 2>&1 &
pids+=("$!")
"$build/client/teleop_bridge" --domain "$domain" --port 0 --stats-s 0 >"$tmp/bridge.log" 2>&1 &
bridge=$!
pids+=("$bridge")
port=""
for _ in $(seq 100); do
  port="$(grep -o 'ws://127.0.0.1:[0-9]*' "$tmp/bridge.log" | head -1 | cut -d: -f3)"
  [ -n "$port" ] && break
  sleep 0.1
done
if [ -z "$port" ]; then
  echo "FAILED: teleop_bridge did not start"
  cat "$tmp/bridge.log"
  exit 1
fi
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
