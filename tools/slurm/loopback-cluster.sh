#!/usr/bin/env bash
# A one-node Slurm cluster on loopback, for trying uvpress-array.sbatch and for the
# cluster integration test (tests/cli/test_slurm.cpp). Everything lives in DIR: its own
# munged (socket and key in DIR), slurmctld and slurmd on free ports, a node with one
# "gpu" GRES (a count, no device file) so that --gres=gpu:1 jobs schedule one at a time.
#
#   tools/slurm/loopback-cluster.sh start DIR   # then: export SLURM_CONF=DIR/slurm.conf
#   tools/slurm/loopback-cluster.sh stop DIR
#
# Needs root and Debian's slurmctld slurmd slurm-client munge (tools/install-deps.sh).
# start exits 77 (skip), with the reason on stderr, when the daemons cannot start.
set -uo pipefail
cmd=${1:-}
dir=${2:-}
[ -n "$cmd" ] && [ -n "$dir" ] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)

stop() {
  for pidfile in "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munged.pid"; do
    [ -f "$pidfile" ] || continue
    pid=$(cat "$pidfile" 2>/dev/null)
    [ -n "$pid" ] && kill "$pid" 2>/dev/null
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null
    rm -f "$pidfile"
  done
}

skip() {
  echo "loopback-cluster: cannot start: $*" >&2
  for log in "$dir"/log/*.log; do [ -f "$log" ] && { echo "--- $log" >&2; tail -n 5 "$log" >&2; }; done
  stop
  exit 77
}

case "$cmd" in
  stop) stop; exit 0 ;;
  start) ;;
  *) echo "usage: $0 start|stop DIR" >&2; exit 2 ;;
esac

[ "$(id -u)" = 0 ] || skip "not root (slurmd runs jobs as their users)"
for tool in munged slurmctld slurmd sbatch scontrol sinfo; do
  command -v "$tool" >/dev/null 2>&1 || skip "$tool is not installed (slurmctld slurmd slurm-client munge)"
done
stop  # leftovers of an earlier run in the same folder
rm -rf "$dir/state" "$dir/spool" "$dir/log"
mkdir -p "$dir/state" "$dir/spool" "$dir/log" "$dir/munge"
chmod 700 "$dir/munge"

# munge: a private key and socket, so that nothing of the machine's own is touched.
head -c 1024 /dev/urandom > "$dir/munge/munge.key"
chmod 600 "$dir/munge/munge.key"
munged --force --socket="$dir/munge/munge.sock" --key-file="$dir/munge/munge.key" \
  --pid-file="$dir/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/munge/seed" \
  >>"$dir/log/munged.log" 2>&1 || skip "munged failed"

# Ports that nothing listens on (a shared machine may run other clusters).
port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
base=$(( 20000 + ($$ % 20000) ))
while ! port_free "$base" || ! port_free $((base + 1)); do base=$((base + 2)); done
host=$(hostname -s)
cpus=$(nproc)
cat > "$dir/slurm.conf" <<EOF
ClusterName=loopback
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$base
SlurmdPort=$((base + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.sock
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
ReturnToService=2
MinJobAge=600
GresTypes=gpu
NodeName=loopback0 NodeAddr=127.0.0.1 NodeHostname=$host CPUs=$cpus RealMemory=2000 Gres=gpu:1 State=UNKNOWN
PartitionName=debug Nodes=loopback0 Default=YES MaxTime=INFINITE State=UP
EOF
printf "AutoDetect=off\nNodeName=loopback0 Name=gpu File=/dev/null Count=1\n" > "$dir/gres.conf"
export SLURM_CONF="$dir/slurm.conf"

slurmctld -c >>"$dir/log/slurmctld.stderr" 2>&1 || skip "slurmctld failed"
slurmd -N loopback0 >>"$dir/log/slurmd.stderr" 2>&1 || skip "slurmd failed"
for _ in $(seq 60); do
  state=$(sinfo -h -N -o %t 2>/dev/null | head -n1)
  [ "$state" = idle ] && { echo "loopback-cluster: up (export SLURM_CONF=$dir/slurm.conf)" >&2; exit 0; }
  case "$state" in inval | drain* | down*) skip "the node is '$state': $(sinfo -h -N -o %E 2>/dev/null | head -n1)" ;; esac
  sleep 0.5
done
skip "the node did not become idle within 30 s (state '${state:-none}')"
