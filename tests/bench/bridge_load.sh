#!/usr/bin/env bash
# What teleop_bridge costs, and what a client that never reads costs it: one server + master
# session (default scene, loopback profile, domain 171) served by teleop_bridge. First a client
# that subscribes to every channel and reads everything for 10 s: the bridge's CPU time and the
# bytes the client got. Then a client that subscribes to every channel and never reads (4 KiB
# receive buffer), the bridge at --queue-kb 256: its RSS every 3 s and its drop counts. The
# clients are small python3 socket programs (no WebSocket library). No assertion: figures for
# docs/tools.md.
#   tests/bench/bridge_load.sh [BUILD_DIR]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${1:-$root/build}"
domain=171  # a benchmark domain (100+), not a test's
export TELEOP_PROFILE=loopback
unset TELEOP_DOMAIN
tmp="$(mktemp -d /tmp/teleop_bridge_load.XXXXXX)"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$tmp"
}
trap cleanup EXIT
cat >"$tmp/client.py" <<'PY'
import json, socket, sys, time
port, seconds, mode = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3]
s = socket.socket()
if mode == "stall":
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
s.connect(("127.0.0.1", port))
s.sendall(b"GET / HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
          b"Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
          b"Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n\r\n")
time.sleep(0.3)
sub = json.dumps({"op": "subscribe",
                  "subscriptions": [{"id": i + 100, "channelId": i} for i in range(1, 12)]}).encode()
s.sendall(bytes([0x81, 0x80 | 126, len(sub) >> 8, len(sub) & 255, 0, 0, 0, 0]) + sub)
n, end = 0, time.time() + seconds
s.settimeout(0.5)
while time.time() < end:
    if mode == "stall":
        time.sleep(0.5)
        continue
    try:
        n += len(s.recv(1 << 20))
    except socket.timeout:
        pass
if mode == "read":
    print(f"client read {n / 1e6:.2f} MB in {seconds:.0f} s ({n / seconds / 1e6:.2f} MB/s)")
PY
run() {  # run MODE QUEUE_KB
  "$build/server/teleop_server" --domain "$domain" --duration 40 --quiet >"$tmp/s.log" 2>&1 &
  local server=$!
  "$build/client/teleop_bridge" --domain "$domain" --port 0 --stats-s 0 --queue-kb "$2" \
    >"$tmp/b.out" 2>"$tmp/b.err" &
  local bridge=$!
  pids+=("$server" "$bridge")
  local port=""
  for _ in $(seq 100); do
    port="$(grep -o '127.0.0.1:[0-9]*' "$tmp/b.out" 2>/dev/null | cut -d: -f2 || true)"
    [ -n "$port" ] && break
    sleep 0.1
  done
  "$build/client/teleop_master" --domain "$domain" --duration 16 --homing 0.5 --quiet \
    >"$tmp/m.log" 2>&1 &
  local master=$!
  pids+=("$master")
  sleep 2
  local tck t0 t1
  tck="$(getconf CLK_TCK)"
  t0="$(awk '{print $14 + $15}' "/proc/$bridge/stat")"
  python3 "$tmp/client.py" "$port" 12 "$1" &
  local client=$!
  if [ "$1" = stall ]; then
    for t in 3 6 9 12; do
      sleep 3
      echo "  t=${t} s bridge $(grep VmRSS "/proc/$bridge/status" | tr -s ' \t' ' ')"
    done
  fi
  wait "$client"
  t1="$(awk '{print $14 + $15}' "/proc/$bridge/stat")"
  echo "  bridge CPU $(( (t1 - t0) * 1000 / tck )) ms over 12 s"
  kill -INT "$bridge"
  wait "$bridge" || true
  grep "done:" "$tmp/b.err" | sed 's/^/  /'
  kill "$server" "$master" 2>/dev/null || true
  wait "$server" "$master" 2>/dev/null || true
}
echo "one client reading every channel (default topics, --queue-kb 4096):"
run read 4096
echo "one client that never reads (--queue-kb 256):"
run stall 256
