#!/usr/bin/env bash
# ctest node.bridge_page_in_chromium: a short live session (teleop_server +
# teleop_master, loopback, this test's domain) served by teleop_bridge; its page (/) opened in
# headless Chromium (Debian's chromium) driven over the DevTools protocol by page_check.mjs, which
# waits for live frames, takes a screenshot and checks that the scene and a moving force trace
# are drawn.
#
#   run_page_check.sh BUILD_DIR DOMAIN [SCREENSHOT.png]
#
# DOMAIN: kNodeBridgePage of tests/support/domains.hpp. Skipped (exit 77) only when node or
# chromium is not installed (deploy/setup.sh with TELEOP_SETUP_TESTS=1 installs both). The
# screenshot goes to BUILD_DIR/bridge_page.png unless named.
set -u
build="$1"
domain="$2"
shot="${3:-$build/bridge_page.png}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
if ! command -v node >/dev/null 2>&1; then
  echo "skipped: node is not installed (deploy/setup.sh installs nodejs and npm)"
  exit 77
fi
chromium="$(command -v chromium || command -v chromium-browser || true)"
if [ -z "$chromium" ]; then
  echo "skipped: chromium is not installed (TELEOP_SETUP_TESTS=1 deploy/setup.sh installs it)"
  exit 77
fi
# shellcheck source=session_lib.sh
. "$here/session_lib.sh"
node_websocket_flags
session_tmp
start_server_and_bridge "$build" "$domain"
timeout 60 "$build/client/teleop_master" --domain "$domain" --duration 14 --homing 0.5 \
  --quiet >"$tmp/master.log" 2>&1 &
pids+=("$!")
node "${node_flags[@]}" "$here/page_check.mjs" "$chromium" "http://127.0.0.1:$port/" "$shot" 12
status=$?
kill -INT "$bridge"
wait "$bridge"
cat "$tmp/bridge.log"
exit "$status"
