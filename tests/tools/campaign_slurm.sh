#!/usr/bin/env bash
# A campaign run through Slurm gives the same table, byte for byte, as the same campaign run on
# this machine. The test starts a single-node Slurm cluster of its own: munged with its own key
# and socket, slurmctld and slurmd on free loopback ports, every file in a temporary folder, run
# as root; `teleop_campaign slurm --submit` sends the array job (4 shards) and the merge job
# after it; the merged table is compared with `teleop_campaign run`'s. Everything it started is
# stopped and removed at the end.
#
#   campaign_slurm.sh BUILD_DIR
#
# Exit status: 0 pass, 1 fail, 77 skipped (printed why: no Slurm or munge, not root, or the
# cluster did not come up).
set -u
build="$1"
campaign="$build/client/campaign/teleop_campaign"
skip() {
  echo "SKIP: $*"
  exit 77
}
fail() {
  echo "FAIL: $*"
  exit 1
}
for exe in slurmctld slurmd munged sbatch squeue sinfo scontrol; do
  command -v "$exe" >/dev/null 2>&1 ||
    skip "$exe not found (apt-get install -y slurmctld slurmd slurm-client munge)"
done
[ "$(id -u)" = "0" ] || skip "the test cluster's daemons run as root; this is uid $(id -u)"
[ -x "$campaign" ] || fail "$campaign not built"

tmp="$(mktemp -d /tmp/teleop_slurm.XXXXXX)"
chmod 755 "$tmp"
pids=()
cleanup() {
  # the jobs first (the cluster is ours alone), then the daemons we started, by their ids
  [ -f "$tmp/slurm.conf" ] && SLURM_CONF="$tmp/slurm.conf" timeout 5 scancel --quiet -u root \
    >/dev/null 2>&1
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do kill "${pids[$i]}" 2>/dev/null; done
  for p in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$p" 2>/dev/null
  done
  rm -rf "$tmp"
}
trap cleanup EXIT

free_port() {
  /usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}
show_logs() {
  for f in "$tmp"/*.log; do
    [ -f "$f" ] && { echo "--- $f"; tail -n 15 "$f"; }
  done
}

# munge: its own key, socket, pid, seed and log
mkdir -p "$tmp/munge"
chmod 700 "$tmp/munge"
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge/munge.key"
munged --foreground --force --key-file="$tmp/munge/munge.key" \
  --socket="$tmp/munge.socket" --pid-file="$tmp/munge/munged.pid" \
  --seed-file="$tmp/munge/munged.seed" --log-file="$tmp/munged.log" >"$tmp/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 50); do [ -S "$tmp/munge.socket" ] && break; sleep 0.1; done
[ -S "$tmp/munge.socket" ] || { show_logs; skip "munged did not start"; }

# slurm: one node (this host as slurmd -C describes it) on loopback ports of its own
host="$(hostname -s)"
node_line="$(slurmd -C 2>/dev/null | head -n 1)"
[ -n "$node_line" ] || skip "slurmd -C does not describe this host"
cpus="$(echo "$node_line" | sed -n 's/.*CPUs=\([0-9]*\).*/\1/p')"
mkdir -p "$tmp/state" "$tmp/spool"
: >"$tmp/plugstack.conf"
cat >"$tmp/slurm.conf" <<EOF
ClusterName=teleoptest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/munge.socket
PlugStackConfig=$tmp/plugstack.conf
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/builtin
SchedulerParameters=sched_interval=1
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
MaxArraySize=1000
$node_line NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$tmp/slurm.conf"
slurmctld -D -i -f "$SLURM_CONF" >"$tmp/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" -N "$host" >"$tmp/slurmd.out" 2>&1 &
pids+=($!)
up=0
for _ in $(seq 100); do
  state="$(sinfo -h -o %T 2>/dev/null | head -n 1)"
  if [ "$state" = "idle" ]; then up=1; break; fi
  sleep 0.2
done
[ "$up" = 1 ] || { show_logs; skip "the test cluster did not come up (node state '${state:-none}')"; }
echo "cluster up: node $host, $cpus CPUs"

# the campaign: 8 point runs of 1.5 s simulated
cat >"$tmp/small.yaml" <<EOF
name: slurm-check
model: point
duration_s: 1.5
sweeps:
  - name: s
    scheme: [position-position, force-position]
    environment: [sphere, wall]
    stiffness_n_per_m: 2000
    delay_ms: [0, 40]
EOF
t0="$(date +%s.%N)"
"$campaign" run "$tmp/small.yaml" --out "$tmp/local" --no-chart --jobs 2 >/dev/null ||
  fail "local run failed"
t1="$(date +%s.%N)"
"$campaign" slurm "$tmp/small.yaml" --out "$tmp/cluster" --shards 4 --submit ||
  { show_logs; fail "teleop_campaign slurm --submit failed"; }
for _ in $(seq 200); do
  [ -f "$tmp/cluster/results.csv" ] && [ -z "$(squeue -h 2>/dev/null)" ] && break
  sleep 0.2
done
t2="$(date +%s.%N)"
[ -f "$tmp/cluster/results.csv" ] || { show_logs; cat "$tmp"/cluster/slurm/*.out; squeue; fail "the merge job wrote no table"; }
tasks="$(ls "$tmp"/cluster/slurm/*_*.out 2>/dev/null | grep -vc merge_)"
[ "$tasks" = 4 ] || fail "expected 4 array task logs, found $tasks"
runs="$(ls "$tmp"/cluster/runs | wc -l)"
[ "$runs" = 8 ] || fail "expected 8 run files, found $runs"
cmp "$tmp/local/results.csv" "$tmp/cluster/results.csv" ||
  fail "the table made through Slurm differs from the local one"
echo "wall time, same 8 runs: local (2 threads) $(echo "$t2 $t1 $t0" | awk '{printf "%.2f", $2 - $3}') s;" \
  "through Slurm (submit, 4 array tasks, merge job) $(echo "$t2 $t1" | awk '{printf "%.2f", $1 - $2}') s"
echo "PASS: 8 runs in 4 array tasks + merge job: the table equals the local run's byte for byte"
