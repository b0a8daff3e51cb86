#!/usr/bin/env bash
# Starts a whole teleoperation session on several hosts over ssh: discovery server(s) if the
# profile needs them, teleop_server, observers (teleop_monitor), then teleop_master in the
# foreground; when the master ends (or on Ctrl-C) everything it started is stopped again.
#
#   deploy/teleop_launch.sh --profile lan|lan_unicast|wan_tcp|discovery
#       --server [USER@]ADDR --master [USER@]ADDR [--observer [USER@]ADDR ...]
#       [--discovery [USER@]ADDR] [--backup-discovery [USER@]ADDR]
#       [--domain 7] [--remote-dir /opt/teleop] [--scene deploy/scenes/default.yaml]
#       [--tcp-port 5100] [--public-address ADDR] [--discovery-port 11811]
#       [--build-dir build] [--ssh "ssh"] [--security-dir DIR | --insecure] [--dry-run]
#       [--session NAME] [--run-dir /tmp/teleop_launch] [-- MASTER_FLAGS...]
#
# ADDR is the host's IPv4 address as the other hosts reach it (also the ssh destination).
# Every host needs the checkout built in --remote-dir (deploy/build.sh) and ssh access by key.
# --build-dir is the build folder relative to --remote-dir (or absolute). --ssh (or
# TELEOP_LAUNCH_SSH) replaces the ssh command; it is called as `SSH [-t] -o OPT... HOST 'CMD'`
# (the multi-host test passes a wrapper that runs CMD in a network namespace instead).
# --dry-run prints every command (one per line) instead of running it. The exit status is the
# master's.
# Each background program's log and pid file are RUN_DIR/SESSION/NAME.log and .pid on its host
# (NAME: server, observer0..., discovery0/1); SESSION defaults to d<DOMAIN>-<UTC time>-<pid of
# this launcher>, so two sessions (on one domain or not) never share a file, and a launcher stops
# only what it started. A --session whose program is still running on a host is refused there.
# Profiles (docs/networking.md): lan (multicast), lan_unicast (every process gets the other
# hosts as --peer), wan_tcp (server wan_tcp_server --listen PORT; the others wan_tcp_client
# --peer SERVER:PORT), discovery (discovery server on --discovery, default the server host;
# --backup-discovery adds a second server, id 1, started with --backup).
# --security-dir DIR (a folder on every host, made by deploy/make_security.sh; each host needs
# only its own identity's folder) runs the secure variant of the profile (secure_lan,
# secure_lan_unicast, secure_wan_tcp_*); each program uses the identity of its role (server,
# master, observer). There is no secure discovery profile. Without --security-dir the plain
# profiles let any host on the network command the slave: the launcher refuses to run them
# unless --insecure is given, and passes --insecure to every program then.
# Exit status 2 for a bad argument (the message names the flag and the value).
set -euo pipefail

profile="" server="" master="" discovery="" backup_discovery=""
observers=()
domain="${TELEOP_DOMAIN:-7}"
remote_dir="/opt/teleop"
scene="deploy/scenes/default.yaml"
tcp_port=5100 discovery_port=11811 public_address=""
dry_run=0
master_extra=()
build_dir="build"
ssh_cmd="${TELEOP_LAUNCH_SSH:-ssh}"
security_dir=""
insecure=0
session=""
run_dir="/tmp/teleop_launch"

die() { echo "teleop_launch: $*" >&2; exit 2; }
need_value() { [ "$#" -ge 2 ] || die "$1 needs a value"; }
while [ "$#" -gt 0 ]; do
  case "$1" in
    --profile) need_value "$@"; profile="$2"; shift 2 ;;
    --server) need_value "$@"; server="$2"; shift 2 ;;
    --master) need_value "$@"; master="$2"; shift 2 ;;
    --observer) need_value "$@"; observers+=("$2"); shift 2 ;;
    --discovery) need_value "$@"; discovery="$2"; shift 2 ;;
    --backup-discovery) need_value "$@"; backup_discovery="$2"; shift 2 ;;
    --domain) need_value "$@"; domain="$2"; shift 2 ;;
    --remote-dir) need_value "$@"; remote_dir="$2"; shift 2 ;;
    --scene) need_value "$@"; scene="$2"; shift 2 ;;
    --tcp-port) need_value "$@"; tcp_port="$2"; shift 2 ;;
    --public-address) need_value "$@"; public_address="$2"; shift 2 ;;
    --discovery-port) need_value "$@"; discovery_port="$2"; shift 2 ;;
    --build-dir) need_value "$@"; build_dir="$2"; shift 2 ;;
    --ssh) need_value "$@"; ssh_cmd="$2"; shift 2 ;;
    --security-dir) need_value "$@"; security_dir="$2"; shift 2 ;;
    --insecure) insecure=1; shift ;;
    --session) need_value "$@"; session="$2"; shift 2 ;;
    --run-dir) need_value "$@"; run_dir="$2"; shift 2 ;;
    --dry-run) dry_run=1; shift ;;
    --) shift; master_extra=("$@"); break ;;
    -h|--help) sed -n '2,/^set -euo pipefail/{/^set/!p}' "$0"; exit 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done

is_ipv4() {
  [[ "$1" =~ ^([0-9]{1,3})\.([0-9]{1,3})\.([0-9]{1,3})\.([0-9]{1,3})$ ]] || return 1
  for o in "${BASH_REMATCH[@]:1}"; do [ "$o" -le 255 ] || return 1; done
}
check_port() {
  if ! { [[ "$2" =~ ^[0-9]{1,5}$ ]] && [ "$2" -ge 1 ] && [ "$2" -le 65535 ]; }; then
    die "$1 '$2' is not a port number in [1, 65535]"
  fi
}
# [USER@]ADDR -> ADDR, checked
addr_of() {
  local flag="$1" spec="$2" a="${2##*@}"
  is_ipv4 "$a" || die "$flag '$spec': '$a' is not an IPv4 address ([USER@]a.b.c.d)"
  echo "$a"
}

case "$profile" in
  lan|lan_unicast|wan_tcp|discovery) ;;
  "") die "--profile is required (lan, lan_unicast, wan_tcp, discovery)" ;;
  *) die "--profile '$profile' is not one of lan, lan_unicast, wan_tcp, discovery" ;;
esac
[ -n "$server" ] || die "--server is required"
[ -n "$master" ] || die "--master is required"
if ! { [[ "$domain" =~ ^[0-9]{1,3}$ ]] && [ "$domain" -le 232 ]; }; then
  die "--domain '$domain' is not an integer in [0, 232]"
fi
[ -n "$session" ] || session="d$domain-$(date -u +%Y%m%dT%H%M%SZ)-$$"
if ! [[ "$session" =~ ^[A-Za-z0-9._-]{1,64}$ ]] || [[ "$session" == .* ]]; then
  die "--session '$session' is not a name of 1-64 letters, digits, '.', '_' or '-' (not starting with '.')"
fi
if ! [[ "$run_dir" =~ ^/[A-Za-z0-9._/-]*$ ]]; then
  die "--run-dir '$run_dir' is not an absolute path of letters, digits, '.', '_', '-' and '/'"
fi
check_port --tcp-port "$tcp_port"
check_port --discovery-port "$discovery_port"
[ -z "$public_address" ] || is_ipv4 "$public_address" ||
  die "--public-address '$public_address' is not an IPv4 address (a.b.c.d)"
server_addr=$(addr_of --server "$server")
master_addr=$(addr_of --master "$master")
observer_addrs=()
for o in "${observers[@]}"; do observer_addrs+=("$(addr_of --observer "$o")"); done
if [ "$profile" = discovery ]; then
  [ -n "$discovery" ] || discovery="$server"
fi
[ -z "$discovery" ] || discovery_addr=$(addr_of --discovery "$discovery")
[ -z "$backup_discovery" ] || backup_addr=$(addr_of --backup-discovery "$backup_discovery")
if [ "$profile" != discovery ] && { [ -n "$discovery" ] || [ -n "$backup_discovery" ]; }; then
  die "--discovery/--backup-discovery need --profile discovery"
fi
if [ -n "$security_dir" ] && [ "$insecure" = 1 ]; then
  die "--insecure and --security-dir '$security_dir' exclude each other"
fi
if [ -z "$security_dir" ] && [ "$insecure" = 0 ]; then
  die "--profile $profile without --security-dir DIR has no DDS Security: any host on the network could command the slave; give --security-dir DIR (deploy/make_security.sh) or accept it with --insecure"
fi
if [ -n "$security_dir" ]; then
  [ "$profile" != discovery ] ||
    die "--security-dir '$security_dir' does not apply to --profile discovery (no secure discovery profile; use lan, lan_unicast or wan_tcp)"
  [[ "$security_dir" =~ ^[A-Za-z0-9_./-]+$ ]] ||
    die "--security-dir '$security_dir': use a path of letters, digits, _ . / - only"
fi

# the network flags of each role
all_addrs=("$server_addr" "$master_addr" "${observer_addrs[@]}")
peers_except() {  # --peer for every host address but $1 (each once)
  local self="$1" a seen=" "
  for a in "${all_addrs[@]}"; do
    [ "$a" = "$self" ] && continue
    case "$seen" in *" $a "*) continue ;; esac
    seen="$seen$a "
    printf -- '--peer %s ' "$a"
  done
}
net_flags() {  # role address; the secure variant with --security-dir
  local flags
  flags="$(plain_net_flags "$@")"
  if [ -n "$security_dir" ]; then
    flags="${flags/--profile /--profile secure_} --security-dir $security_dir"
  else
    flags="$flags --insecure"
  fi
  echo "$flags"
}
plain_net_flags() {  # role address
  local role="$1" self="$2"
  case "$profile" in
    lan) echo "--profile lan" ;;
    lan_unicast) echo "--profile lan_unicast $(peers_except "$self")" ;;
    wan_tcp)
      if [ "$role" = server ]; then
        echo "--profile wan_tcp_server --listen $tcp_port${public_address:+ --public-address $public_address}"
      else
        echo "--profile wan_tcp_client --peer ${public_address:-$server_addr}:$tcp_port"
      fi ;;
    discovery)
      echo "--profile discovery_client --discovery-server $discovery_addr:$discovery_port${backup_discovery:+ --discovery-server $backup_addr:$discovery_port}" ;;
  esac
}

ssh_opts=(-o BatchMode=yes -o ConnectTimeout=10)
started=()  # "host pidfile" of everything started in the background
run() {  # print (dry run) or execute
  if [ "$dry_run" = 1 ]; then
    printf '%s\n' "$*"
  else
    eval "$*"
  fi
}
start_bg() {  # host name command...
  local host="$1" name="$2"; shift 2
  local dir="$run_dir/$session"
  local pidfile="$dir/$name.pid" log="$dir/$name.log"
  # `cd || exit; nohup ... &` (not `cd && nohup ... &`, which would background a subshell and
  # record its pid instead of the program's); a live pid in the file is another launcher's
  local busy="echo \"teleop_launch: $host: $pidfile: session $session is running there\" >&2; exit 1"
  run "$ssh_cmd ${ssh_opts[*]} $host 'cd $remote_dir || exit 1; mkdir -p $dir || exit 1; if [ -s $pidfile ] && kill -0 \$(cat $pidfile) 2>/dev/null; then $busy; fi; nohup $* > $log 2>&1 < /dev/null & echo \$! > $pidfile'"
  started+=("$host $pidfile")
}
stop_all() {  # in reverse order: observers, server, then discovery servers
  local e host pidfile k
  for ((k = ${#started[@]} - 1; k >= 0; k--)); do
    e="${started[$k]}"
    host="${e%% *}"; pidfile="${e#* }"
    run "$ssh_cmd ${ssh_opts[*]} $host 'kill \$(cat $pidfile) 2>/dev/null; rm -f $pidfile'" || true
  done
}
[ "$dry_run" = 1 ] || trap stop_all EXIT INT TERM
echo "teleop_launch: session $session: logs and pid files in $run_dir/$session/ on each host" >&2

if [ "$profile" = discovery ]; then
  start_bg "$discovery" discovery0 "deploy/teleop_discovery.sh --id 0 --address $discovery_addr --port $discovery_port"
  if [ -n "$backup_discovery" ]; then
    start_bg "$backup_discovery" discovery1 "deploy/teleop_discovery.sh --id 1 --address $backup_addr --port $discovery_port --backup --backup-dir /var/tmp/teleop-discovery"
  fi
fi
start_bg "$server" server "$build_dir/server/teleop_server --domain $domain --scene $scene $(net_flags server "$server_addr")"
i=0
for o in "${observers[@]}"; do
  start_bg "$o" "observer$i" "$build_dir/client/teleop_monitor --domain $domain $(net_flags observer "${observer_addrs[$i]}")"
  i=$((i + 1))
done
master_rc=0
run "$ssh_cmd -t ${ssh_opts[*]} $master 'cd $remote_dir && $build_dir/client/teleop_master --domain $domain $(net_flags master "$master_addr") ${master_extra[*]}'" ||
  master_rc=$?
if [ "$dry_run" = 1 ]; then stop_all; fi
exit "$master_rc"
