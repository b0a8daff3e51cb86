#!/usr/bin/env bash
# The master's haptic loop over TCP (wan_tcp profiles) with and without a link cut, in a
# private network the script builds itself: network namespaces "server" and "master" joined by a
# bridge in a third namespace (nothing is added to the machine's own namespace; everything is
# removed at exit). The cut detaches the master's port from the bridge for CUT seconds, so the
# master's packets vanish silently, as on a broken WAN path. Needs root and iproute2.
#
# Each run prints, from the master's per-cycle log and summary:
#   issued      commands issued / (session length x rate): the cycles the loop issued
#   gap_ms      the longest gap between two consecutive cycles (the loop's period held?)
#   step_n      the largest change of the rendered force between two cycles [N]
#   detect_ms   cut start -> first cycle with link_ok 0 (cut runs)
#
#   tests/bench/tcp_link_cut.sh [--build DIR] [--runs N] [--cut SECONDS] [--duration SECONDS]
#                               [--master-flags "FLAGS"]
#                               [--profile wan_tcp|lan|secure_wan_tcp|secure_lan|loopback]
#
#   --build DIR      folder holding server/teleop_server and client/teleop_master, or both
#                    executables directly (default: build)
#   --runs N         sessions of each kind, without and with a cut (default 3)
#   --cut SECONDS    length of the cut (default 1)
#   --duration S     master session length after homing (default 8)
#   --master-flags F more teleop_master flags, e.g. "--realtime 20" (default none)
#   --profile P      wan_tcp (default: wan_tcp_server / wan_tcp_client), lan (UDP, multicast),
#                    secure_wan_tcp, secure_lan (the same with DDS Security: files made by
#                    deploy/make_security.sh into a temporary folder), or loopback (both
#                    programs in the server's namespace: no cut runs; the loop's own share of
#                    missed cycles on this machine, for comparison)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="$root/build"
runs=3
cut=1
duration=8
master_flags=""
profile=wan_tcp
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --cut) cut="$2"; shift 2 ;;
    --duration) duration="$2"; shift 2 ;;
    --master-flags) master_flags="$2"; shift 2 ;;
    --profile) profile="$2"; shift 2 ;;
    -h | --help) sed -n '2,29p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "tcp_link_cut.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[[ "$runs" =~ ^[0-9]+$ ]] && [ "$runs" -ge 1 ] || { echo "tcp_link_cut.sh: --runs '$runs' is not an integer >= 1" >&2; exit 2; }
[[ "$cut" =~ ^[0-9.]+$ ]] || { echo "tcp_link_cut.sh: --cut '$cut' is not a number of seconds" >&2; exit 2; }
[[ "$duration" =~ ^[0-9]+$ ]] && [ "$duration" -ge 4 ] || { echo "tcp_link_cut.sh: --duration '$duration' is not an integer >= 4" >&2; exit 2; }
master_ns_is_server=0
case "$profile" in
  wan_tcp)
    server_net=(--profile wan_tcp_server --listen 5100 --public-address 10.78.0.1 --insecure)
    master_net=(--profile wan_tcp_client --peer 10.78.0.1:5100 --insecure) ;;
  lan) server_net=(--profile lan --insecure); master_net=(--profile lan --insecure) ;;
  secure_wan_tcp | secure_lan)
    sec_dir="$(mktemp -d)"
    "$root/deploy/make_security.sh" --no-other --identity server:server --identity master:master \
      "$sec_dir" >/dev/null
    if [ "$profile" = secure_lan ]; then
      server_net=(--profile secure_lan --security-dir "$sec_dir")
      master_net=(--profile secure_lan --security-dir "$sec_dir")
    else
      server_net=(--profile secure_wan_tcp_server --listen 5100 --public-address 10.78.0.1
        --security-dir "$sec_dir")
      master_net=(--profile secure_wan_tcp_client --peer 10.78.0.1:5100 --security-dir "$sec_dir")
    fi ;;
  loopback) server_net=(--profile loopback); master_net=(--profile loopback); master_ns_is_server=1 ;;
  *) echo "tcp_link_cut.sh: --profile '$profile' is not one of wan_tcp, lan, secure_wan_tcp, secure_lan, loopback" >&2; exit 2 ;;
esac
server_bin="$build/server/teleop_server"; master_bin="$build/client/teleop_master"
[ -x "$server_bin" ] || server_bin="$build/teleop_server"
[ -x "$master_bin" ] || master_bin="$build/teleop_master"
[ -x "$server_bin" ] && [ -x "$master_bin" ] || { echo "tcp_link_cut.sh: --build '$build' holds no teleop_server / teleop_master" >&2; exit 2; }
[ "$(id -u)" = 0 ] || { echo "tcp_link_cut.sh: needs root (network namespaces)" >&2; exit 2; }
py="$(command -v /usr/bin/python3 || command -v python3 || true)"
[ -n "$py" ] || { echo "tcp_link_cut.sh: needs python3 for the analysis" >&2; exit 2; }

tag="tlc$$"; sw="${tag}sw"; hs="${tag}s"; hm="${tag}m"
work="$(mktemp -d /tmp/tcp_link_cut.XXXXXX)"
cleanup() {
  for ns in "$hs" "$hm" "$sw"; do
    for pid in $(ip netns pids "$ns" 2>/dev/null); do kill -9 "$pid" 2>/dev/null || true; done
    ip netns del "$ns" 2>/dev/null || true
  done
  rm -rf "$work"
  [ -z "${sec_dir:-}" ] || rm -rf "$sec_dir"
}
trap cleanup EXIT
ip netns add "$sw"; ip -n "$sw" link set lo up
ip -n "$sw" link add br0 type bridge mcast_snooping 0; ip -n "$sw" link set br0 up
i=1
for h in "$hs" "$hm"; do
  ip netns add "$h"; ip -n "$h" link set lo up
  ip -n "$h" link add eth0 type veth peer name "p$i" netns "$sw"
  ip -n "$h" addr add "10.78.0.$i/24" dev eth0; ip -n "$h" link set eth0 up
  ip -n "$h" route add 224.0.0.0/4 dev eth0
  ip -n "$sw" link set "p$i" master br0; ip -n "$sw" link set "p$i" up
  i=$((i + 1))
done

run() {  # run KIND N: one session; KIND = plain | cut
  local kind="$1" n="$2" d=173
  local log="$work/${kind}_$n.csv" json="$work/${kind}_$n.json"
  ip netns exec "$hs" "$server_bin" --domain "$d" "${server_net[@]}" --duration 60 --quiet --scene "$root/deploy/scenes/default.yaml" \
    > "$work/server.out" 2>&1 &
  local spid=$!
  local mns="$hm"
  [ "$master_ns_is_server" = 1 ] && mns="$hs"
  ip netns exec "$mns" "$master_bin" --domain "$d" "${master_net[@]}" \
    --duration "$duration" --homing 0.5 --wait-server 20 --log "$log" --summary-json "$json" \
    --quiet $master_flags > "$work/master.out" 2>&1 &
  local mpid=$!
  local cut_at=""
  if [ "$kind" = cut ]; then
    # the cut starts once the session runs (the log's phase column turns 1) plus 2 s
    for _ in $(seq 200); do
      [ -f "$log" ] && awk -F, 'NR > 1 && $2 == 1 { f = 1; exit } END { exit !f }' "$log" && break
      sleep 0.1
    done
    sleep 2
    cut_at="$(awk -F, 'END { print $1 }' "$log")"
    ip -n "$sw" link set p2 nomaster
    sleep "$cut"
    ip -n "$sw" link set p2 master br0
  fi
  local rc=0
  wait "$mpid" || rc=$?
  kill -TERM "$spid" 2>/dev/null || true
  wait "$spid" 2>/dev/null || true
  "$py" - "$log" "$json" "$kind" "$n" "$rc" "${cut_at:-nan}" "$profile" <<'EOF'
import csv, json, math, sys
log, js, kind, n, rc, cut_at = sys.argv[1:7]
rows = list(csv.DictReader(open(log)))
t = [float(r["t_s"]) for r in rows]
f = [(float(r["fm_x"]), float(r["fm_y"]), float(r["fm_z"])) for r in rows]
gap = max((b - a for a, b in zip(t, t[1:])), default=float("nan"))
step = max((math.dist(a, b) for a, b in zip(f, f[1:])), default=float("nan"))
s = json.load(open(js))
issued = s["issued"] / (s["duration_s"] * s["rate_hz"])
detect = float("nan")
cut_at = float(cut_at)
if not math.isnan(cut_at):
    lost = [float(r["t_s"]) for r in rows if float(r["t_s"]) >= cut_at and r["link_ok"] in ("0", "0.0")]
    if lost: detect = (lost[0] - cut_at) * 1e3
print(f"{sys.argv[7]} {kind:5s} run {n}: rc {rc}  issued {issued * 100:.2f} % ({s['issued']} in {s['duration_s']:.2f} s)"
      f"  overruns {s['overruns']}  gap_ms {gap * 1e3:.1f}  step_n {step:.4f}  detect_ms {detect:.0f}"
      f"  link_losses {s['link_losses']}  stalls {s['stalls']['count']} (longest {s['stalls']['longest_s']:.3f} s)"
      f"  verdict {s['verdict']}")
EOF
}

for n in $(seq "$runs"); do run plain "$n"; done
[ "$master_ns_is_server" = 1 ] || for n in $(seq "$runs"); do run cut "$n"; done
