#!/usr/bin/env bash
# Remakes the pictures and data of docs/results/ with the commands the docs name, one recipe
# per group of files, each run in a folder of its own and only its declared files copied in.
#   deploy/make_docs.sh                 every recipe (the benchmarks take minutes each)
#   deploy/make_docs.sh --quick         the ten recipes under a minute each
#   deploy/make_docs.sh --only a,b      the named recipes
#   deploy/make_docs.sh --list          recipes, their cost and their files
#   deploy/make_docs.sh --check [ROOT]  every file in docs/results has a recipe (or is archived)
#                                       and every docs/results file the docs link exists
# RESULTS_OUT=DIR writes the files there instead of docs/results (to compare before replacing).
# The recipes whose figures the docs give for the paper's scene run it explicitly (paper_scene
# below), not the default scene (the FEM ball).
# BUILD_DIR (default build/) must hold the programs: cmake --build build --target teleop_server
# teleop_master teleop_viewer teleop_experiment teleop_bench teleop_campaign.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$root/build}"
results="$root/docs/results"
out="${RESULTS_OUT:-$results}"  # where remade files go (RESULTS_OUT=DIR to compare first)
py=/usr/bin/python3
paper_scene="$root/deploy/scenes/paper_sphere.yaml"  # the PUMA 560 over the paper's sphere

# name | cost (quick: under a minute; bench: minutes) | files written into docs/results
recipes=(
  "session|quick|experiment3_master.json experiment3_server.json experiment3_session.png experiment3_force_deformation.png"
  "viewer|quick|viewer.png"
  "viewer-drive|quick|viewer_drive.png"
  "bridge-page|quick|bridge_page.png"
  "sphere-zero-g|quick|sphere_zero_g.png"
  "navier-free-vertex|quick|navier_free_vertex.png"
  "navier-held-vertex|quick|navier_held_vertex.png"
  "sphere-gravity|quick|sphere_gravity.png"
  "robot-reach|quick|robot_reach.png robot_reach_summary.csv"
  "contact-force-curve|quick|contact_force_curve.csv contact_force_curve.png contact_force_fit.csv"
  "delay|bench|delay_map.csv delay_boundary.csv delay_theory.csv delay_summary.json delay_map.png delay_map_tdpa.png delay_map_passive.png transparency.png"
  "campaign-delay-map|bench|campaign_delay_map.png"
  "campaign-default-scene|bench|campaign_default_scene.csv campaign_default_scene.png campaign_default_scene_transparency.png"
  "rtt|bench|rtt.csv rtt.png"
  "world|bench|world.csv world.png"
  "robot|bench|robot_bench.csv robot_bench.png"
  "collision|bench|collision_bench.csv collision_bench.png"
  "growth|bench|growth.csv growth.png growth_fit.csv"
  "peers|bench|peers.csv peers.png peers_trace.csv"
  "peers-fem|bench|peers_fem.csv peers_fem.png"
  "live|bench|live.csv"
  "live-fifo|bench|live_fifo.csv"
  "live-nice|bench|live_nice.csv"
  "observers|bench|observers.csv observers.png"
  "observers-per-host|bench|observers_per_host.csv observers_per_host_scaling.csv"
  "validate|bench|validation.csv validation.png"
  "deformable|bench|deformable.csv deformable.png"
)
# Kept from particular runs and not remade here: another machine (xeon16/: a 16-core Xeon,
# docs/results.md says which commands) and two observer runs the docs compare with.
archived=(xeon16 observers_quiet.csv observers_quiet.png observers_run1.csv)

die() { echo "make_docs: $*" >&2; exit 2; }

recipe_field() {  # recipe_field NAME INDEX
  local r
  for r in "${recipes[@]}"; do
    IFS='|' read -r n c f <<<"$r"
    if [ "$n" = "$1" ]; then
      case "$2" in 1) echo "$c" ;; 2) echo "$f" ;; esac
      return 0
    fi
  done
  return 1
}

check() {  # check [ROOT]: ROOT's docs/results and docs (default: this checkout)
  local root="${1:-$root}"
  local results="$root/docs/results"
  local status=0 declared=" ${archived[*]} " r n c f entry link
  for r in "${recipes[@]}"; do
    IFS='|' read -r n c f <<<"$r"
    declared+="$f "
  done
  for entry in "$results"/*; do
    entry="$(basename "$entry")"
    if [[ "$declared" != *" $entry "* ]]; then
      echo "make_docs: docs/results/$entry has no recipe in deploy/make_docs.sh" >&2
      status=1
    fi
  done
  for entry in $declared; do
    if [ ! -e "$results/$entry" ]; then
      echo "make_docs: a recipe declares docs/results/$entry but it does not exist" >&2
      status=1
    fi
  done
  while IFS= read -r link; do
    if [ ! -e "$results/$link" ]; then
      echo "make_docs: the docs link results/$link, which does not exist" >&2
      status=1
    fi
  done < <(grep -rhoE "results/[A-Za-z0-9_./-]+\.(png|csv|json)" "$root/docs" "$root/README.md" |
    sed -E 's|.*results/||' | sort -u)
  [ "$status" -eq 0 ] && echo "make_docs: docs/results and its recipes agree (${#recipes[@]} recipes)"
  return "$status"
}

# paper_data_dir DIR: a data folder (TELEOP_DATA_DIR, common/util/data_dir.hpp) whose
# scenes/default.yaml is the paper's scene and whose other scenes are the shipped ones, for the
# programs a recipe cannot give a --scene (the sessions the test and bench scripts start); the
# other data folders (profiles, data, charts) still come from the source tree
paper_data_dir() {
  local dir="$1/data" f
  mkdir -p "$dir/scenes"
  for f in "$root"/deploy/scenes/*; do ln -s "$f" "$dir/scenes/$(basename "$f")"; done
  rm "$dir/scenes/default.yaml"
  cp "$paper_scene" "$dir/scenes/default.yaml"
  echo "$dir"
}

need() {  # need PROGRAM...: the build must hold them
  local p
  for p in "$@"; do [ -x "$build/$p" ] || die "$build/$p is missing: build it first (see the header of this script)"; done
}

# a live server + master session, as deploy/run_session.sh runs it, on the paper's scene
run_session() {  # run_session DIR DOMAIN [master flags...]
  local dir="$1" domain="$2"
  shift 2
  need server/teleop_server client/teleop_master
  "$build/server/teleop_server" --scene "$paper_scene" --domain "$domain" --quiet \
    --realtime 20 --summary-json "$dir/server.json" &
  local server_pid=$! status=0
  "$build/client/teleop_master" --domain "$domain" --realtime 20 --log "$dir/master.csv" \
    --summary-json "$dir/master.json" --quiet "$@" || status=$?
  kill -TERM "$server_pid"
  wait "$server_pid" || true
  return "$status"
}

xvfb() { xvfb-run -a -s "-screen 0 1280x720x24" "$@"; }

run_recipe() {  # run_recipe NAME DIR: writes the recipe's files into DIR
  local name="$1" dir="$2" exp="$build/server/teleop_experiment" bench="$build/tests/bench/teleop_bench"
  case "$name" in
    session)
      run_session "$dir" 57
      "$py" "$root/tests/charts/session.py" "$dir/master.csv" "$dir" \
        "experiment 3: $(grep -o '"scheme": "[^"]*"' "$dir/master.json" | cut -d'"' -f4), paper's scene"
      mv "$dir/master.json" "$dir/experiment3_master.json"
      mv "$dir/server.json" "$dir/experiment3_server.json"
      mv "$dir/session.png" "$dir/experiment3_session.png"
      mv "$dir/force_deformation.png" "$dir/experiment3_force_deformation.png" ;;
    viewer)
      need client/teleop_viewer
      "$build/server/teleop_server" --scene "$paper_scene" --domain 58 --quiet --duration 40 &
      local server_pid=$!
      sleep 2
      "$build/client/teleop_master" --domain 58 --script press-slip --quiet >/dev/null &
      local master_pid=$!
      xvfb "$build/client/teleop_viewer" --domain 58 --snapshot "$dir/viewer.png" --after 4.8
      kill "$master_pid" "$server_pid" 2>/dev/null || true
      wait "$master_pid" "$server_pid" 2>/dev/null || true ;;
    viewer-drive)
      need client/teleop_viewer
      printf '%s\n' "1.0 key pagedown 0.4" "2.5 tune force_gain 1.5 ramp_s 0.5" \
        "4.0 drag 12 0 0.6" "5.0 snapshot $dir/viewer_drive.png" "6.5 quit" >"$dir/drive.txt"
      "$build/server/teleop_server" --scene "$paper_scene" --domain 59 --quiet --duration 60 &
      local server_pid=$!
      "$build/client/teleop_master" --domain 59 --device external --accept-tuning \
        --duration 20 --quiet >/dev/null &
      local master_pid=$!
      xvfb "$build/client/teleop_viewer" --domain 59 --drive --input-script "$dir/drive.txt" \
        --duration 40 --fps 20
      kill "$master_pid" "$server_pid" 2>/dev/null || true
      wait "$master_pid" "$server_pid" 2>/dev/null || true ;;
    bridge-page)
      need client/teleop_bridge
      TELEOP_DATA_DIR="$(paper_data_dir "$dir")" \
        bash "$root/tests/node/run_page_check.sh" "$build" 203 "$dir/bridge_page.png" ;;
    sphere-zero-g | navier-free-vertex | navier-held-vertex | sphere-gravity | robot-reach | \
      contact-force-curve)
      need server/teleop_experiment
      "$exp" "$name" --out "$dir" --no-progress ;;
    validate)
      need server/teleop_experiment
      "$exp" validate --out "$dir" --no-progress ;;
    delay) need tests/bench/teleop_bench; "$bench" delay --out "$dir" --no-progress ;;
    campaign-delay-map | campaign-default-scene)
      need client/campaign/teleop_campaign
      local file=delay_map
      [ "$name" = campaign-default-scene ] && file=default_scene
      "$build/client/campaign/teleop_campaign" run "$root/deploy/campaigns/$file.yaml" \
        --out "$dir/run" --jobs "$(nproc)" --no-progress
      if [ "$file" = delay_map ]; then
        cp "$dir/run/stability_map.png" "$dir/campaign_delay_map.png"
      else
        cp "$dir/run/results.csv" "$dir/campaign_default_scene.csv"
        cp "$dir/run/stability_map.png" "$dir/campaign_default_scene.png"
        cp "$dir/run/transparency.png" "$dir/campaign_default_scene_transparency.png"
      fi ;;
    rtt | robot | collision | growth | peers-fem)
      need tests/bench/teleop_bench
      "$bench" "$name" --out "$dir" --no-progress ;;
    world)
      need tests/bench/teleop_bench
      "$bench" world --scene "$paper_scene" --out "$dir" --no-progress ;;
    peers) need tests/bench/teleop_bench; "$bench" peers --out "$dir" --rounds 5 --no-progress ;;
    live)
      need tests/bench/teleop_bench
      "$bench" observers --live 1 --scene "$paper_scene" --out "$dir" --counts 0,8 --rounds 3 \
        --duration 6 --domain 215 --no-progress --variants \
        normal,spin250,prewarm250+spin250,dma0,pin,fifo20,mlock ;;
    live-fifo)
      need tests/bench/teleop_bench
      "$bench" observers --live 1 --scene "$paper_scene" --out "$dir" --counts 0,8 --rounds 3 \
        --duration 6 --domain 216 --no-progress --variants \
        prewarm250,fifo20,fifo20+spin250,fifo20+prewarm250+spin250,fifo20+dma0,fifo20+pin,fifo20+mlock
      mv "$dir/live.csv" "$dir/live_fifo.csv" ;;
    live-nice)
      need tests/bench/teleop_bench
      "$bench" observers --live 1 --scene "$paper_scene" --out "$dir" --counts 0,8 --rounds 3 \
        --duration 6 --domain 217 --variants normal,nice-20,fifo20 --no-progress
      mv "$dir/live.csv" "$dir/live_nice.csv" ;;
    observers)
      need tests/bench/teleop_bench
      # without --live the bench has no --scene: its server reads the data folder's default
      TELEOP_DATA_DIR="$(paper_data_dir "$dir")" "$bench" observers --out "$dir" --rounds 4 \
        --full-rate-counts 8,16,32 --nice0-counts 32 --no-progress ;;
    observers-per-host)
      need tests/bench/teleop_bench
      TELEOP_DATA_DIR="$(paper_data_dir "$dir")" "$bench" observers --out "$dir" --quick \
        --counts 0,8,16,32,64 --rounds 3 --duration 5 --domain 196 --no-chart
      mv "$dir/observers.csv" "$dir/observers_per_host.csv"
      mv "$dir/observers_scaling.csv" "$dir/observers_per_host_scaling.csv" ;;
    deformable) need tests/bench/teleop_bench; "$bench" deformable --out "$dir" --no-progress ;;
    *) die "no recipe '$name'" ;;
  esac
}

mode=all only=""
while [ $# -gt 0 ]; do
  case "$1" in
    --list) mode=list; shift ;;
    --check)
      mode=check check_root=""
      if [ $# -ge 2 ] && [ "${2#-}" = "$2" ]; then check_root="$2"; shift; fi
      shift ;;
    --quick) mode=quick; shift ;;
    --only)
      [ $# -ge 2 ] && [ -n "$2" ] || die "--only needs recipe names, e.g. --only viewer,rtt"
      mode=only only="$2"; shift 2 ;;
    -h | --help) sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) die "unknown argument '$1' (allowed: --list, --check, --quick, --only NAMES)" ;;
  esac
done

case "$mode" in
  list)
    for r in "${recipes[@]}"; do
      IFS='|' read -r n c f <<<"$r"
      printf '%-24s %-6s %s\n' "$n" "$c" "$f"
    done
    printf '%-24s %-6s %s\n' "(archived)" "-" "${archived[*]}"
    exit 0 ;;
  check) check ${check_root:+"$check_root"}; exit $? ;;
esac

selected=()
for r in "${recipes[@]}"; do
  IFS='|' read -r n c f <<<"$r"
  case "$mode" in
    all) selected+=("$n") ;;
    quick) [ "$c" = quick ] && selected+=("$n") ;;
  esac
done
if [ "$mode" = only ]; then
  IFS=',' read -r -a selected <<<"$only"
  for n in "${selected[@]}"; do recipe_field "$n" 1 >/dev/null || die "--only: no recipe '$n' (deploy/make_docs.sh --list)"; done
fi

work="$(mktemp -d /tmp/teleop_make_docs.XXXXXX)"
trap 'rm -rf "$work"' EXIT
failed=()
for n in "${selected[@]}"; do
  dir="$work/$n"
  mkdir -p "$dir"
  start=$(date +%s)
  echo "== $n ($(recipe_field "$n" 1)) =="
  if ! (run_recipe "$n" "$dir") >"$work/$n.log" 2>&1; then
    echo "make_docs: recipe $n failed (its output: below)" >&2
    tail -n 20 "$work/$n.log" >&2
    failed+=("$n")
    continue
  fi
  missing=0
  for f in $(recipe_field "$n" 2); do
    if [ ! -s "$dir/$f" ]; then echo "make_docs: recipe $n did not write $f" >&2; missing=1; fi
  done
  if [ "$missing" -ne 0 ]; then failed+=("$n"); continue; fi
  for f in $(recipe_field "$n" 2); do
    mkdir -p "$out"
    cp "$dir/$f" "$out/$f" || { echo "make_docs: cannot write $out/$f" >&2; exit 1; }
    # a file no doc names is not an error (grep's status 1 would end the script under pipefail)
    cited=$(grep -rlF "$f" "$root/docs" "$root/README.md" 2>/dev/null | sed "s|$root/||" |
      sort -u | tr '\n' ' ' || true)
    echo "   $f${cited:+ (cited by $cited)}"
  done
  echo "   $(($(date +%s) - start)) s"
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "make_docs: failed: ${failed[*]}" >&2
  exit 1
fi
echo "make_docs: ${#selected[@]} recipes remade; check the numbers the docs quote from the files above"
