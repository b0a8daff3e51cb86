#!/usr/bin/env bash
# The main job: set up, build and install the session's programs (deploy/build.sh --session,
# then cmake --install into PREFIX, default out/install), run a teleoperation session on the
# default scene with the installed teleop_server and teleop_master as separate processes on
# loopback, print a summary and write charts.
#   deploy/run_session.sh [--duration S] [--out DIR] [extra teleop_master flags, e.g.
#                         --scheme force-position --delay 20ms --jitter 2ms --loss 1%]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
duration=0   # 0: the operator script's length (about 9 s)
out="$root/out/session"
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --duration) duration="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    *) extra+=("$1"); shift ;;
  esac
done
bash "$root/deploy/build.sh" --session
build_dir="${BUILD_DIR:-$root/build}"
prefix="${PREFIX:-$root/out/install}"
cmake --install "$build_dir" --prefix "$prefix" --component runtime >/dev/null
echo "installed into $prefix ($("$prefix/bin/teleop_server" --version))"
mkdir -p "$out"
domain="${TELEOP_DOMAIN:-7}"

echo "== teleop session (experiment 3): default scene, loopback, domain ${domain} =="
# the installed programs read their scene and profiles from $prefix/share/teleop
# both loops SCHED_FIFO where the machine allows it (a warning and normal threads otherwise):
# docs/results.md, "Live session"
"$prefix/bin/teleop_server" --domain "$domain" --quiet --realtime 20 \
  --summary-json "$out/server.json" &
server_pid=$!
trap 'kill $server_pid 2>/dev/null || true' EXIT
# the master's exit status says its verdict (docs/exit_codes.md): the charts are drawn whatever
# it is, and the script exits with it
master_status=0
"$prefix/bin/teleop_master" --domain "$domain" --duration "$duration" --realtime 20 \
  --log "$out/master.csv" --summary-json "$out/master.json" "${extra[@]}" || master_status=$?
kill -TERM "$server_pid"
wait "$server_pid" || true
trap - EXIT
# 1-4: no session was judged (an error, a bad flag, no server, refused): nothing to draw
if [ "$master_status" -ge 1 ] && [ "$master_status" -le 4 ]; then exit "$master_status"; fi

/usr/bin/python3 "$prefix/share/teleop/charts/session.py" "$out/master.csv" "$out" \
  "experiment 3: $(grep -o '"scheme": "[^"]*"' "$out/master.json" | cut -d'"' -f4), default scene" \
  && echo "charts: $out/session.png $out/force_deformation.png"
echo "server summary: $out/server.json"
echo "master summary: $out/master.json"
exit "$master_status"
