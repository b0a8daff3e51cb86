#!/usr/bin/env bash
# Round trip of the master without teleop_record, with it writing MCAP and with it writing
# SQLite: the same server + master session (loopback profile, domain 101, 1 kHz), the three
# alternated RUNS times. Prints the master's round-trip p50/p99 of every run, and for a recording
# its counts, its file size per second of session and the recorder's CPU time per second of
# session (user + system, from /proc, the recorder's whole life: 1 s of discovery before the
# session and the final write after it). No assertion: figures for docs/tools.md.
#   tests/bench/record_overhead.sh [BUILD_DIR] [SECONDS] [RUNS] [SCENE]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${1:-$root/build}"
secs="${2:-10}"
runs="${3:-2}"
scene="${4:-$root/deploy/scenes/default.yaml}"
domain=101
tmp="$(mktemp -d /tmp/teleop_record_overhead.XXXXXX)"
trap 'rm -rf "$tmp"' EXIT
field() { /usr/bin/python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(d$2)" "$1"; }

session() {  # $1 = without|mcap|sqlite, $2 = run index
  local tag="$1_$2" rec_pid="" file=""
  if [ "$1" != without ]; then
    file="$tmp/$tag.$([ "$1" = mcap ] && echo mcap || echo db)"
    "$build/client/teleop_record" --domain $domain --out "$file" \
      --summary-json "$tmp/$tag.rec.json" --quiet &
    rec_pid=$!
    sleep 1
  fi
  "$build/server/teleop_server" --domain $domain --duration $((secs + 30)) --scene "$scene" \
    >"$tmp/$tag.server.out" 2>&1 &
  local srv_pid=$!
  "$build/client/teleop_master" --domain $domain --duration "$secs" --quiet \
    --summary-json "$tmp/$tag.master.json" >/dev/null 2>&1
  kill -TERM $srv_pid; wait $srv_pid || true
  local cpu_ticks=0
  if [ -n "$rec_pid" ]; then
    sleep 0.3
    # utime + stime of the recorder (fields 14, 15 of /proc/PID/stat) just before it stops
    cpu_ticks=$(awk '{print $14 + $15}' "/proc/$rec_pid/stat")
    kill -INT $rec_pid; wait $rec_pid || true
  fi
  local p50 p99
  p50=$(field "$tmp/$tag.master.json" "['rtt_ms']['p50']")
  p99=$(field "$tmp/$tag.master.json" "['rtt_ms']['p99']")
  printf '%-8s run %d: rtt p50 %.3f ms  p99 %.3f ms' "$1" "$2" "$p50" "$p99"
  if [ -n "$rec_pid" ]; then
    local bytes
    bytes=$(stat -c %s "$file")
    printf '  | %s samples, gaps %s, dropped %s, file %s bytes = %.0f kB/s, recorder CPU %.0f %%' \
      "$(field "$tmp/$tag.rec.json" "['samples']")" "$(field "$tmp/$tag.rec.json" "['gaps']")" \
      "$(field "$tmp/$tag.rec.json" "['dropped']")" "$bytes" \
      "$(awk -v b="$bytes" -v s="$secs" 'BEGIN {print b / s / 1000}')" \
      "$(awk -v t="$cpu_ticks" -v hz="$(getconf CLK_TCK)" -v s="$secs" 'BEGIN {print 100 * t / hz / s}')"
  fi
  printf '\n'
}

echo "scene $(basename "$scene"), ${secs} s sessions, $runs runs each way, domain $domain"
for i in $(seq 1 "$runs"); do
  session without "$i"
  session mcap "$i"
  session sqlite "$i"
done
