#!/usr/bin/env bash
# Set up, build, and run the whole test suite with ctest (2 jobs), then the short fuzz runs
# (build-fuzz, clang; TELEOP_FUZZ=0 skips them) and clang-tidy on the changed code
# (deploy/tidy.sh --changed; TELEOP_TIDY=0 skips it). Exit status: non-zero if any failed.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/deploy/build.sh" --tests
build_dir="${BUILD_DIR:-$root/build}"
cd "$build_dir"
status=0
ctest -j2 --output-on-failure --timeout 600 "$@" || status=$?
# clang-tidy (.clang-tidy, every finding an error) on what changed since the last clean full run
# (.ci/tidy-clean; deploy/tidy.sh --all checks everything); TELEOP_TIDY=0 skips it
if [ "${TELEOP_TIDY:-1}" != "0" ]; then
  BUILD_DIR="$build_dir" bash "$root/deploy/tidy.sh" --changed || status=1
fi
# The short fuzz runs (tests/fuzz: replay the committed corpus, then ~25 s per fuzzer) live in a
# clang build folder of their own (build-fuzz: only the fuzz targets and the sources they use).
# TELEOP_FUZZ=0 skips them; without clang they are skipped with a message.
if [ "${TELEOP_FUZZ:-1}" != "0" ]; then
  if command -v clang++ >/dev/null 2>&1; then
    fuzz_dir="${FUZZ_BUILD_DIR:-$root/build-fuzz}"
    if [ ! -f "$fuzz_dir/CMakeCache.txt" ]; then
      # shellcheck disable=SC2086
      cmake -S "$root" -B "$fuzz_dir" -G Ninja ${CMAKE_ARGS:-} -DCMAKE_C_COMPILER=clang \
        -DCMAKE_CXX_COMPILER=clang++ -DTELEOP_BUILD_FUZZERS=ON -DTELEOP_BUILD_TESTS=OFF \
        -DTELEOP_BUILD_BENCHMARKS=OFF -DTELEOP_BUILD_VIEWER=OFF
    fi
    cmake --build "$fuzz_dir" -j2 --target fuzzers
    (cd "$fuzz_dir" && ctest -j2 --output-on-failure --timeout 300 -L fuzz) || status=$?
  else
    echo "run_tests.sh: clang++ not found: the fuzz runs are skipped (apt-get install clang)"
  fi
fi
exit $status
