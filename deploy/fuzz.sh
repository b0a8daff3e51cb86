#!/usr/bin/env bash
# Long fuzz runs (docs/testing.md, "Fuzzing"). Configures and builds the libFuzzer targets with
# clang in a build folder of their own (default build-fuzz; the main GCC build is not touched),
# then runs each fuzzer for SECONDS (default 600) from the committed seed corpus into a working
# corpus that grows across runs (build-fuzz/fuzz-work/<name>/corpus). Crashing inputs land in
# build-fuzz/fuzz-work/<name>/crashes/: minimise one with `FUZZER -minimize_crash=1 FILE`, fix the
# bug, and commit the input into tests/fuzz/corpus/<name>/regression_<what> so every test run
# replays it. Prints executions, executions per second and crashes of each fuzzer.
#
#   deploy/fuzz.sh [SECONDS] [scene|mesh|command|mcap ...]     e.g. deploy/fuzz.sh 3600 scene
#   JOBS=2 deploy/fuzz.sh 600        # libFuzzer -jobs/-workers per fuzzer (default 1)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${FUZZ_BUILD_DIR:-$root/build-fuzz}"
seconds="${1:-600}"
shift || true
names=("$@")
[ ${#names[@]} -eq 0 ] && names=(scene mesh command mcap)
jobs="${JOBS:-1}"
command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ not found (apt-get install clang)" >&2; exit 2; }
if [ ! -f "$build/CMakeCache.txt" ]; then
  # shellcheck disable=SC2086
  cmake -S "$root" -B "$build" -G Ninja ${CMAKE_ARGS:-} -DCMAKE_C_COMPILER=clang \
    -DCMAKE_CXX_COMPILER=clang++ -DTELEOP_BUILD_FUZZERS=ON -DTELEOP_BUILD_TESTS=OFF \
    -DTELEOP_BUILD_BENCHMARKS=OFF -DTELEOP_BUILD_VIEWER=OFF
fi
cmake --build "$build" -j2 --target fuzzers
status=0
for name in "${names[@]}"; do
  work="$build/fuzz-work/$name"
  mkdir -p "$work/corpus" "$work/crashes"
  dict=()
  [ -f "$root/tests/fuzz/$name.dict" ] && dict=(-dict="$root/tests/fuzz/$name.dict")
  echo "== fuzz_$name: $seconds s, $jobs job(s)"
  log="$work/last_run.log"
  parallel=()
  [ "$jobs" -gt 1 ] && parallel=(-jobs="$jobs" -workers="$jobs")
  set +e
  # from the work folder: with -jobs libFuzzer writes fuzz-N.log into the current folder
  (cd "$work" && "$build/tests/fuzz/fuzz_$name" -max_total_time="$seconds" -max_len=8192 \
    -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$work/crashes/" \
    "${dict[@]}" "${parallel[@]}" "$work/corpus" "$root/tests/fuzz/corpus/$name") >"$log" 2>&1
  rc=$?
  set -e
  grep -E "stat::number_of_executed_units|stat::average_exec_per_sec|stat::new_units_added" "$log" |
    sed "s/^/   /" || true
  crashes=$(find "$work/crashes" -type f | wc -l)
  echo "   crashes so far: $crashes (in $work/crashes), exit status $rc, log $log"
  [ "$rc" -ne 0 ] && status=1
done
exit $status
