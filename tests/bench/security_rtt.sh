#!/usr/bin/env bash
# Round-trip cost of DDS Security: sessions of teleop_server (tool-only scene) and teleop_master
# on loopback, alternating the plain `loopback` profile and the `secure` profile, RUNS times
# each; prints each run's master round trip (rtt_ms p50 / p99) and the medians over the runs.
# Loopback only, domains 110 (plain) and 111 (secure).
#
#   tests/bench/security_rtt.sh [--build DIR] [--runs N] [--samples N] [--csv FILE]
#
#   --build DIR    build folder holding server/teleop_server and client/teleop_master (build)
#   --runs N       sessions per profile (default 5)
#   --samples N    commands per session at 1 kHz (default 5000)
#   --csv FILE     also write one row per session (profile,run,sent,received,rtt_p50_ms,rtt_p99_ms)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="$root/build"
runs=5
samples=5000
csv=""
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --samples) samples="$2"; shift 2 ;;
    --csv) csv="$2"; shift 2 ;;
    -h | --help) sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "security_rtt.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[[ "$runs" =~ ^[0-9]+$ ]] && [ "$runs" -ge 1 ] || { echo "security_rtt.sh: --runs '$runs' is not an integer >= 1" >&2; exit 2; }
[[ "$samples" =~ ^[0-9]+$ ]] && [ "$samples" -ge 100 ] || { echo "security_rtt.sh: --samples '$samples' is not an integer >= 100" >&2; exit 2; }
server="$build/server/teleop_server"
master="$build/client/teleop_master"
for b in "$server" "$master"; do
  [ -x "$b" ] || { echo "security_rtt.sh: $b not built (--build DIR)" >&2; exit 2; }
done

work="$(mktemp -d /tmp/teleop_security_rtt.XXXXXX)"
server_pid=""
cleanup() {
  [ -n "$server_pid" ] && kill "$server_pid" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
bash "$root/deploy/make_security.sh" --no-other "$work/certs" >/dev/null

# session PROFILE DOMAIN JSON: one server + master session; the master's summary into JSON
session() {
  local profile="$1" domain="$2" json="$3" sec=()
  [ "$profile" = secure ] && sec=(--security-dir "$work/certs")
  "$server" --profile "$profile" "${sec[@]}" --domain "$domain" --duration 120 --quiet \
    --scene "$root/deploy/scenes/tool_only.yaml" >"$work/server.out" 2>&1 &
  server_pid=$!
  if ! "$master" --profile "$profile" "${sec[@]}" --domain "$domain" --samples "$samples" \
    --quiet --summary-json "$json" >"$work/master.out" 2>&1; then
    echo "security_rtt.sh: master failed ($profile):" >&2
    cat "$work/master.out" >&2
    exit 1
  fi
  kill -TERM "$server_pid"
  wait "$server_pid" || true
  server_pid=""
}

# fields of a master summary: sent received p50 p99
fields() {
  /usr/bin/python3 -c '
import json, sys
m = json.load(open(sys.argv[1]))
print(m["sent"], m["received"], m["rtt_ms"]["p50"], m["rtt_ms"]["p99"])' "$1"
}

results="$work/results.txt"
: >"$results"
printf '%-9s %4s %13s %10s %10s\n' profile run received rtt_p50_ms rtt_p99_ms
for run in $(seq 1 "$runs"); do
  for profile in loopback secure; do
    domain=110
    [ "$profile" = secure ] && domain=111
    session "$profile" "$domain" "$work/m.json"
    read -r sent received p50 p99 <<<"$(fields "$work/m.json")"
    echo "$profile $run $sent $received $p50 $p99" >>"$results"
    printf '%-9s %4s %6s/%-6s %10.3f %10.3f\n' "$profile" "$run" "$received" "$sent" "$p50" "$p99"
  done
done

if [ -n "$csv" ]; then
  echo "profile,run,sent,received,rtt_p50_ms,rtt_p99_ms" >"$csv"
  tr ' ' ',' <"$results" >>"$csv"
fi

/usr/bin/python3 - "$results" <<'EOF'
import statistics, sys
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
print()
print(f"medians over the runs ({len(rows) // 2} per profile):")
med = {}
for profile in ("loopback", "secure"):
    r = [x for x in rows if x[0] == profile]
    p50 = statistics.median(float(x[4]) for x in r)
    p99 = statistics.median(float(x[5]) for x in r)
    rec = sum(int(x[3]) for x in r) / max(1, sum(int(x[2]) for x in r))
    med[profile] = (p50, p99)
    print(f"  {profile:9s} rtt p50 {p50:.3f} ms  p99 {p99:.3f} ms  received {100 * rec:.2f} %")
d50 = med["secure"][0] - med["loopback"][0]
d99 = med["secure"][1] - med["loopback"][1]
print(f"  secure - loopback: p50 {d50:+.3f} ms, p99 {d99:+.3f} ms")
EOF
