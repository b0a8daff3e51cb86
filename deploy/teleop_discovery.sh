#!/usr/bin/env bash
# Starts a Fast DDS discovery server for the `discovery_client` profile (docs/networking.md),
# around Debian's fast-discovery-server (package fastdds-tools; `fastdds discovery` is the same
# tool behind a Python front end).
#
#   deploy/teleop_discovery.sh [--id N] [--address ADDR] [--port PORT] [--backup]
#                              [--backup-dir DIR] [--dry-run]
#
#   --id N          server id, 0-255 (default 0). Clients list the servers in id order:
#                   --discovery-server ADDR_OF_ID0:PORT --discovery-server ADDR_OF_ID1:PORT
#   --address ADDR  IPv4 address to listen on (default 0.0.0.0: every interface)
#   --port PORT     UDP port (default 11811)
#   --backup        BACKUP server: keeps its discovery state in files and restores it when
#                   restarted (in --backup-dir, default the current directory). Run a second
#                   server with another id on another host for redundancy.
#   --dry-run       print the command instead of running it
# Environment defaults: TELEOP_DISCOVERY_ID, TELEOP_DISCOVERY_ADDRESS, TELEOP_DISCOVERY_PORT.
# Exit status 2 for a bad argument (the message names the flag and the value).
set -euo pipefail

id="${TELEOP_DISCOVERY_ID:-0}"
address="${TELEOP_DISCOVERY_ADDRESS:-0.0.0.0}"
port="${TELEOP_DISCOVERY_PORT:-11811}"
backup=0
backup_dir=""
dry_run=0

die() { echo "teleop_discovery: $*" >&2; exit 2; }
need_value() { [ "$#" -ge 2 ] || die "$1 needs a value"; }

while [ "$#" -gt 0 ]; do
  case "$1" in
    --id) need_value "$@"; id="$2"; shift 2 ;;
    --address) need_value "$@"; address="$2"; shift 2 ;;
    --port) need_value "$@"; port="$2"; shift 2 ;;
    --backup) backup=1; shift ;;
    --backup-dir) need_value "$@"; backup_dir="$2"; shift 2 ;;
    --dry-run) dry_run=1; shift ;;
    -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done

is_uint() { [[ "$1" =~ ^[0-9]{1,5}$ ]]; }
is_ipv4() {
  [[ "$1" =~ ^([0-9]{1,3})\.([0-9]{1,3})\.([0-9]{1,3})\.([0-9]{1,3})$ ]] || return 1
  for o in "${BASH_REMATCH[@]:1}"; do [ "$o" -le 255 ] || return 1; done
}
{ is_uint "$id" && [ "$id" -le 255 ]; } || die "--id '$id' is not an integer in [0, 255]"
is_ipv4 "$address" || die "--address '$address' is not an IPv4 address (a.b.c.d)"
{ is_uint "$port" && [ "$port" -ge 1 ] && [ "$port" -le 65535 ]; } ||
  die "--port '$port' is not a port number in [1, 65535]"
[ "$backup" = 1 ] || [ -z "$backup_dir" ] || die "--backup-dir needs --backup"

if command -v fast-discovery-server >/dev/null 2>&1; then
  cmd=(fast-discovery-server)
elif command -v fastdds >/dev/null 2>&1; then
  cmd=(fastdds discovery)
else
  if [ "$dry_run" = 1 ]; then
    cmd=(fast-discovery-server)
  else
    echo "teleop_discovery: neither fast-discovery-server nor fastdds found (install fastdds-tools)" >&2
    exit 1
  fi
fi
cmd+=(-i "$id" -l "$address" -p "$port")
[ "$backup" = 1 ] && cmd+=(-b)

if [ "$dry_run" = 1 ]; then
  [ -n "$backup_dir" ] && printf 'cd %q && ' "$backup_dir"
  printf '%q ' "${cmd[@]}"; echo
  exit 0
fi
if [ -n "$backup_dir" ]; then
  mkdir -p "$backup_dir"
  cd "$backup_dir"
fi
exec "${cmd[@]}"
