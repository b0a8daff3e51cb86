#!/usr/bin/env bash
# Set up, build, and run the whole test suite with ctest (2 jobs). Exit status is ctest's.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/deploy/build.sh"
build_dir="${BUILD_DIR:-$root/build}"
cd "$build_dir"
ctest -j2 --output-on-failure --timeout 600 "$@"
