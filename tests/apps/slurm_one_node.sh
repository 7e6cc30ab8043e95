#!/usr/bin/env bash
# A one-node Slurm cluster started by hand in a folder of its own, for tests/apps/slurm_array_test:
# its own munged (key, socket, logs), slurm.conf (proctrack/linuxproc, task/none, loopback, its
# own ports and state folders), slurmctld and slurmd in the foreground, their pids in DIR/*.pid.
#
#   slurm_one_node.sh start DIR   # prints SLURM_CONF=DIR/slurm.conf once the node is idle
#   slurm_one_node.sh stop DIR    # stops the daemons it started (by their pids), always safe
#
# Root only (slurmd runs jobs as their users; munged and slurmd check their files' owners).
set -euo pipefail

what=${1:-} dir=${2:-}
[[ -n $what && -n $dir ]] || { echo "usage: slurm_one_node.sh start|stop DIR" >&2; exit 2; }

stop() {
  # All three at once (each takes 1.5-2 s to go), by the pids recorded; KILL after 5 s.
  local pids=()
  for name in slurmd slurmctld munged; do
    local pidfile=$dir/$name.pid
    [[ -f $pidfile ]] || continue
    local pid
    pid=$(cat "$pidfile")
    rm -f "$pidfile"
    if [[ $pid =~ ^[0-9]+$ ]] && kill -0 "$pid" 2>/dev/null; then
      kill -TERM "$pid" 2>/dev/null || true
      pids+=("$pid")
    fi
  done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$pid" 2>/dev/null || true
  done
}

if [[ $what == stop ]]; then
  stop
  exit 0
fi
[[ $what == start ]] || { echo "slurm_one_node.sh: unknown command $what" >&2; exit 2; }

mkdir -p "$dir"/{munge,state,spool,log}
chmod 700 "$dir/munge"
dir=$(cd "$dir" && pwd)
trap 'stop' ERR

# munged with its own key and socket.
dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$dir/munge/munge.key"
munged --foreground --force --key-file="$dir/munge/munge.key" --socket="$dir/munge/socket" \
  --pid-file="$dir/munge/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/munge/seed" \
  >"$dir/log/munged.out" 2>&1 &
echo $! >"$dir/munged.pid"
for _ in $(seq 50); do [[ -S $dir/munge/socket ]] && break; sleep 0.1; done
[[ -S $dir/munge/socket ]] || { echo "slurm_one_node.sh: munged did not start:" >&2; cat "$dir/log/munged.log" "$dir/log/munged.out" >&2; false; }

# Ports of its own: two free ones above 20000, from this shell's pid.
port=$((20000 + ($$ % 20000) * 2))
cpus=$(nproc)
host=$(hostname -s) # slurmctld runs only where SlurmctldHost names this machine
cat >"$dir/slurm.conf" <<CONF
ClusterName=symbtest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge/socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/state/slurmctld.pid
SlurmdPidFile=$dir/spool/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
SlurmctldTimeout=10
SlurmdTimeout=10
MessageTimeout=5
NodeName=symbtest NodeAddr=127.0.0.1 NodeHostname=localhost CPUs=$cpus State=UNKNOWN
PartitionName=test Nodes=symbtest Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$dir/slurm.conf

slurmctld -D -i -f "$SLURM_CONF" >"$dir/log/slurmctld.out" 2>&1 &
echo $! >"$dir/slurmctld.pid"
slurmd -D -N symbtest -f "$SLURM_CONF" >"$dir/log/slurmd.out" 2>&1 &
echo $! >"$dir/slurmd.pid"

# Ready once the node is idle (at most 20 s; sinfo waits long for a controller that is not up).
deadline=$((SECONDS + 20))
while ((SECONDS < deadline)); do
  state=$(timeout 2 sinfo -h -n symbtest -o %t 2>/dev/null || true)
  [[ $state == idle ]] && { echo "SLURM_CONF=$SLURM_CONF"; exit 0; }
  kill -0 "$(cat "$dir/slurmctld.pid")" 2>/dev/null || break
  sleep 0.2
done
echo "slurm_one_node.sh: the node did not become idle (state '${state:-}'):" >&2
tail -n 20 "$dir/log/slurmctld.log" "$dir/log/slurmd.log" "$dir/log/slurmctld.out" "$dir/log/slurmd.out" >&2 || true
false
