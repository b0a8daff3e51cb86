#!/usr/bin/env bash
# Installs missing packages (Debian's, and the npm packages of tests/node), configures and
# builds (-j2). Used by run_session.sh and run_tests.sh. BUILD_DIR (default: build) and
# CMAKE_ARGS may be set by the caller.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${BUILD_DIR:-$root/build}"
bash "$root/deploy/setup.sh"
# the npm packages of the MCAP test (tests/node), exactly as its package-lock.json lists them;
# installed again only when the lockfile changed (no install scripts: none of them needs one)
if command -v npm >/dev/null 2>&1; then
  stamp="$root/tests/node/node_modules/.teleop-package-lock.json"
  if ! cmp -s "$root/tests/node/package-lock.json" "$stamp"; then
    (cd "$root/tests/node" && npm ci --ignore-scripts --no-audit --no-fund)
    cp "$root/tests/node/package-lock.json" "$stamp"
  fi
fi
generator=()
command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
if [ ! -f "$build_dir/CMakeCache.txt" ]; then
  # shellcheck disable=SC2086
  cmake -S "$root" -B "$build_dir" "${generator[@]}" ${CMAKE_ARGS:-}
fi
cmake --build "$build_dir" -j2
