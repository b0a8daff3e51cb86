#!/usr/bin/env bash
# What 1, 10 and 50 WebSocket clients of teleop_bridge cost: one server + master session
# (default scene, loopback profile, domain 202, a 12 s press-slip session) with no bridge, then
# served by teleop_bridge to N clients (one Node process, tests/bench/bridge_clients.mjs), each
# subscribed to every channel and reading everything. Per run: the bridge's CPU over the 8 s
# from 2 s into the session (from /proc/PID/stat, % of one core), its RSS at the end and its
# peak (VmHWM), the bytes the clients read, and the master's round-trip p99 (its summary JSON).
# Each row is the median of RUNS runs (default 3). The clients share the 2 cores with the
# session: their cost is in the round trip too. No assertion: figures for docs/results.md.
#   tests/bench/bridge_clients.sh [BUILD_DIR] [RUNS]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${1:-$root/build}"
runs="${2:-3}"
domain=202  # tests/support/domains.hpp: a benchmark domain
export TELEOP_PROFILE=loopback
unset TELEOP_DOMAIN
node_flags=()
if ! node -e 'process.exit(typeof WebSocket === "function" ? 0 : 1)' 2>/dev/null; then
  node_flags=(--experimental-websocket)
fi
tmp="$(mktemp -d /tmp/teleop_bridge_clients.XXXXXX)"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$tmp"
}
trap cleanup EXIT
tck="$(getconf CLK_TCK)"

# one N: prints "cpu_pct rss_mib hwm_mib mb_read rtt_p99_ms"
one() {
  local n="$1" bridge="" port="" client=""
  "$build/server/teleop_server" --domain "$domain" --duration 40 --quiet >"$tmp/s.log" 2>&1 &
  local server=$!
  pids+=("$server")
  if [ "$n" -gt 0 ]; then
    "$build/client/teleop_bridge" --domain "$domain" --port 0 --stats-s 0 --max-clients 64 \
      >"$tmp/b.out" 2>"$tmp/b.err" &
    bridge=$!
    pids+=("$bridge")
    for _ in $(seq 100); do
      port="$(grep -o 'ws://127.0.0.1:[0-9]*' "$tmp/b.out" 2>/dev/null | cut -d: -f3 || true)"
      [ -n "$port" ] && break
      sleep 0.1
    done
    node "${node_flags[@]}" "$root/tests/bench/bridge_clients.mjs" "ws://127.0.0.1:$port" "$n" 14 \
      >"$tmp/c.out" &
    client=$!
    pids+=("$client")
  fi
  "$build/client/teleop_master" --domain "$domain" --duration 12 --homing 0.5 --quiet \
    --summary-json "$tmp/m.json" >"$tmp/m.log" 2>&1 &
  local master=$!
  pids+=("$master")
  sleep 2
  local t0=0 t1=0 rss=0 hwm=0
  [ -n "$bridge" ] && t0="$(awk '{print $14 + $15}' "/proc/$bridge/stat")"
  sleep 8
  if [ -n "$bridge" ]; then
    t1="$(awk '{print $14 + $15}' "/proc/$bridge/stat")"
    rss="$(awk '/VmRSS/ {print $2}' "/proc/$bridge/status")"
    hwm="$(awk '/VmHWM/ {print $2}' "/proc/$bridge/status")"
  fi
  wait "$master" || true
  local mb=0
  if [ -n "$client" ]; then
    wait "$client" || true
    mb="$(awk '{printf "%.1f", $8 / 1e6}' "$tmp/c.out")"
    kill -INT "$bridge"
    wait "$bridge" || true
  fi
  kill "$server" 2>/dev/null || true
  wait "$server" 2>/dev/null || true
  local p99
  p99="$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["rtt_ms"]["p99"])' "$tmp/m.json")"
  echo "$(( (t1 - t0) * 100 / tck / 8 )) $(( rss / 1024 )) $(( hwm / 1024 )) $mb $p99"
}

median() { sort -g | awk '{a[NR] = $1} END {print a[int((NR + 1) / 2)]}'; }

printf '%-8s %12s %10s %10s %12s %14s\n' clients bridge_cpu_% rss_MiB peak_MiB MB_read rtt_p99_ms
for n in 0 1 10 50; do
  : >"$tmp/rows"
  for _ in $(seq "$runs"); do one "$n" >>"$tmp/rows"; done
  cols=()
  for c in 1 2 3 4 5; do cols+=("$(cut -d' ' -f"$c" "$tmp/rows" | median)"); done
  label="$n"
  [ "$n" -eq 0 ] && label="none"
  printf '%-8s %12s %10s %10s %12s %14s\n' "$label" "${cols[@]}"
  echo "  runs: $(tr '\n' ';' <"$tmp/rows")"
done
