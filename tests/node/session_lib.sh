# Shared by the tests/node/run_*_check.sh scripts (sourced): Node's WebSocket flag, a temporary
# folder with every started process killed at exit, and a live teleop_server + teleop_bridge on
# this test's domain, loopback only.

# node_flags: Node 22 has a WebSocket client built in; Node 20.10+ behind a flag
node_websocket_flags() {
  node_flags=()
  if ! node -e 'process.exit(typeof WebSocket === "function" ? 0 : 1)' 2>/dev/null; then
    node_flags=(--experimental-websocket)
  fi
}

# tmp: a temporary folder; pids: processes to stop; both cleaned up at exit
session_tmp() {
  export TELEOP_PROFILE=loopback
  unset TELEOP_DOMAIN
  tmp="$(mktemp -d)"
  pids=()
  trap session_cleanup EXIT
}
session_cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done
  wait 2>/dev/null
  rm -rf "$tmp"
}

# start_server_and_bridge BUILD DOMAIN [BRIDGE_FLAG...]: teleop_server, then teleop_bridge
# (default flags --port 0: a port the system picks; given flags replace them); sets bridge (its
# pid) and port from the ws:// or wss:// address it prints, or exits 1 naming what did not start
start_server_and_bridge() {
  local build="$1" domain="$2"
  shift 2
  local flags=("$@")
  [ "${#flags[@]}" -gt 0 ] || flags=(--port 0)
  "$build/server/teleop_server" --domain "$domain" --duration 60 --quiet >"$tmp/server.log" 2>&1 &
  pids+=("$!")
  "$build/client/teleop_bridge" --domain "$domain" "${flags[@]}" --stats-s 0 >"$tmp/bridge.log" 2>&1 &
  bridge=$!
  pids+=("$bridge")
  port=""
  for _ in $(seq 100); do
    port="$(grep -oE 'wss?://127.0.0.1:[0-9]*' "$tmp/bridge.log" | head -1 | cut -d: -f3)"
    [ -n "$port" ] && break
    sleep 0.1
  done
  if [ -z "$port" ]; then
    echo "FAILED: teleop_bridge ${flags[*]} did not start"
    cat "$tmp/bridge.log"
    exit 1
  fi
}
