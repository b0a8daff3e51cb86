#!/usr/bin/env bash
# ctest node.bridge_access: teleop_bridge's access rules.
#  1. flags refused with exit 2 and a message naming them: a non-loopback --listen without TLS
#     and a token, a short token file, --tls-cert without --tls-key, unreadable TLS files;
#  2. a bridge with TLS (a self-signed certificate made by openssl in this test's temp folder)
#     and an access token on 127.0.0.1, in front of a live teleop_server: access_check.mjs
#     checks that a client with the token is served and one without is refused (401), and the
#     bridge's summary counts the refusals.
# Every socket is on 127.0.0.1 (the non-loopback address of 1. is refused before it binds).
#
#   run_access_check.sh BUILD_DIR DOMAIN
#
# DOMAIN: kNodeBridgeAccess of tests/support/domains.hpp. Skipped (exit 77) only when node or
# openssl is not installed.
set -u
build="$1"
domain="$2"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
bridge_bin="$build/client/teleop_bridge"
for tool in node openssl; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "skipped: $tool is not installed (deploy/setup.sh installs it)"
    exit 77
  fi
done
# shellcheck source=session_lib.sh
. "$here/session_lib.sh"
node_websocket_flags
session_tmp
failed=0

# refused: status 2 and every word in $2.. in the message
expect_refused() {
  local args="$1"
  shift
  # shellcheck disable=SC2086
  "$bridge_bin" --domain "$domain" --duration 1 $args >"$tmp/out" 2>&1
  local status=$?
  if [ "$status" -ne 2 ]; then
    echo "FAIL teleop_bridge $args: status $status, expected 2"
    failed=1
  fi
  for word in "$@"; do
    if ! grep -q -- "$word" "$tmp/out"; then
      echo "FAIL teleop_bridge $args: the message does not name $word: $(cat "$tmp/out")"
      failed=1
    fi
  done
  echo "  refused (status $status): $args"
}
openssl req -x509 -newkey rsa:2048 -nodes -keyout "$tmp/key.pem" -out "$tmp/cert.pem" -days 2 \
  -subj /CN=127.0.0.1 -addext subjectAltName=IP:127.0.0.1 >/dev/null 2>&1
openssl rand -hex 24 >"$tmp/token"
echo short >"$tmp/short"
expect_refused "--listen 0.0.0.0:0" --tls-cert --tls-key --token-file --insecure-listen
expect_refused "--listen 0.0.0.0:0 --tls-cert $tmp/cert.pem --tls-key $tmp/key.pem" --token-file
expect_refused "--listen 127.0.0.1:99999" --listen 65535
expect_refused "--listen 127.0.0.1:0 --token-file $tmp/short" --token-file "$tmp/short" 16-4096
expect_refused "--tls-cert $tmp/cert.pem" --tls-cert --tls-key
expect_refused "--port 0 --tls-cert $tmp/none.pem --tls-key $tmp/key.pem" "$tmp/none.pem"
expect_refused "--port 0 --tls-cert $tmp/key.pem --tls-key $tmp/key.pem" "$tmp/key.pem" certificate

start_server_and_bridge "$build" "$domain" --listen 127.0.0.1:0 --tls-cert "$tmp/cert.pem" \
  --tls-key "$tmp/key.pem" --token-file "$tmp/token"
NODE_EXTRA_CA_CERTS="$tmp/cert.pem" node "${node_flags[@]}" "$here/access_check.mjs" \
  "https://127.0.0.1:$port" "$(cat "$tmp/token")" || failed=1
kill -INT "$bridge"
wait "$bridge"
cat "$tmp/bridge.log"
# the page without a token, with a wrong one, wss without and with a wrong token: at least 4
refused="$(grep -o '[0-9]* without the token' "$tmp/bridge.log" | tail -1 | cut -d' ' -f1)"
if [ -z "$refused" ] || [ "$refused" -lt 4 ]; then
  echo "FAIL the bridge counted ${refused:-no} requests without the token (at least 4 expected)"
  failed=1
fi
exit "$failed"
