#!/usr/bin/env bash
# Installs missing packages, configures and builds (-j2). Used by run_session.sh and run_tests.sh.
#   deploy/build.sh --session   the session's packages and targets only: teleop_server,
#                               teleop_master, the libraries they link, the viewer where its
#                               packages exist (tests, benchmarks and tools off)
#   deploy/build.sh [--tests]   everything: the tools, tests and benchmarks too (their packages,
#                               and the npm packages of tests/node)
# Both use one build folder (BUILD_DIR, default: build): --tests after --session reconfigures and
# builds only what was left out. CMAKE_ARGS may be set by the caller (after the options below, so
# it can override them); the folder is configured again when the mode or CMAKE_ARGS change.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${BUILD_DIR:-$root/build}"
mode=tests
case "${1:-}" in
  --session) mode=session ;;
  --tests | "") mode=tests ;;
  *)
    echo "deploy/build.sh: unknown argument '$1' (allowed: --session, --tests)" >&2
    exit 2
    ;;
esac

if [ "$mode" = "session" ]; then
  bash "$root/deploy/setup.sh"
  options=(-DTELEOP_BUILD_TESTS=OFF -DTELEOP_BUILD_BENCHMARKS=OFF -DTELEOP_BUILD_TOOLS=OFF)
else
  TELEOP_SETUP_TESTS=1 bash "$root/deploy/setup.sh"
  options=(-DTELEOP_BUILD_TESTS=ON -DTELEOP_BUILD_BENCHMARKS=ON -DTELEOP_BUILD_TOOLS=ON)
  # the npm packages of the MCAP test (tests/node), exactly as its package-lock.json lists
  # them; installed again only when the lockfile changed (no install scripts: none needs one)
  if command -v npm >/dev/null 2>&1; then
    stamp="$root/tests/node/node_modules/.teleop-package-lock.json"
    if ! cmp -s "$root/tests/node/package-lock.json" "$stamp"; then
      (cd "$root/tests/node" && npm ci --ignore-scripts --no-audit --no-fund)
      cp "$root/tests/node/package-lock.json" "$stamp"
    fi
  fi
fi
generator=()
command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
# shellcheck disable=SC2206
args=("${options[@]}" ${CMAKE_ARGS:-})
args_stamp="$build_dir/.teleop-build-args"
if [ ! -f "$build_dir/CMakeCache.txt" ] || [ "$(cat "$args_stamp" 2>/dev/null)" != "${args[*]}" ]; then
  if [ -f "$build_dir/CMakeCache.txt" ]; then
    cmake -S "$root" -B "$build_dir" "${args[@]}"
  else
    cmake -S "$root" -B "$build_dir" "${generator[@]}" "${args[@]}"
  fi
  printf '%s' "${args[*]}" >"$args_stamp"
fi
cmake --build "$build_dir" -j2
