#!/usr/bin/env bash
# Stand-in for ssh in the multi-host test: `netns_ssh.sh [-t] [-o OPT]... [USER@]ADDR 'CMD'`
# runs CMD with bash inside the network namespace that TELEOP_NETNS_MAP
# ("10.77.0.1=ns1,10.77.0.2=ns2,...") gives for ADDR, as ssh would run it on that host.
set -euo pipefail
while [ "$#" -gt 0 ]; do
  case "$1" in
    -t) shift ;;
    -o) shift 2 ;;
    *) break ;;
  esac
done
[ "$#" -eq 2 ] || { echo "netns_ssh: usage: [-t] [-o OPT]... HOST 'COMMAND'" >&2; exit 255; }
addr="${1##*@}"
ns=""
IFS=',' read -r -a pairs <<< "${TELEOP_NETNS_MAP:-}"
for p in "${pairs[@]}"; do
  [ "${p%%=*}" = "$addr" ] && ns="${p#*=}"
done
[ -n "$ns" ] || { echo "netns_ssh: no namespace for host $addr" >&2; exit 255; }
exec "${TELEOP_IP:-ip}" netns exec "$ns" bash -c "$2"
