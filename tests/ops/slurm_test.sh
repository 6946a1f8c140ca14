#!/usr/bin/env bash
# The Slurm batch script for real (issue 16): a single-node Slurm (Debian's
# munged, slurmctld and slurmd, private sockets, ports and spool under a
# temporary directory) runs ops/slurm/fabatlas-workers.sbatch against a
# coordinator with TLS and a bearer token. The fabatlas job must succeed on
# the Slurm-started workers; then `scancel --signal=TERM` drains them and the
# Slurm job must end COMPLETED with exit code 0:0.
#   tests/ops/slurm_test.sh SOURCE_DIR BIN_DIR
# Exit 77 (skipped, with the reason) only when not root or Slurm is missing.
set -euo pipefail
src=$(cd "${1:?source dir}" && pwd)
bin=$(cd "${2:?bin dir}" && pwd)
if [[ $(id -u) != 0 ]]; then echo "SKIP: starting slurmctld, slurmd and munged needs root"; exit 77; fi
for p in munged slurmctld slurmd sbatch scontrol sinfo; do
  command -v "$p" >/dev/null || { echo "SKIP: $p not installed (ops/install-deps.sh installs Slurm)"; exit 77; }
done

tmp=$(mktemp -d /tmp/fabatlas-slurm.XXXXXX)
chmod 755 "$tmp"
pids=()
cleanup() {
  local rc=$?
  # Last started first: the coordinator and slurmd before slurmctld, munged last.
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do kill "${pids[i]}" 2>/dev/null || true; wait "${pids[i]}" 2>/dev/null || true; done
  if [[ $rc != 0 ]]; then
    for f in "$tmp"/*.log "$tmp"/slurm-*.out; do [[ -f $f ]] && { echo "== $f"; tail -n 30 "$f"; }; done
  fi
  rm -rf "$tmp"
}
trap cleanup EXIT
free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
wait_for() {  # seconds command...: polls the command every 0.2 s until it succeeds
  local n=$(( $1 * 5 )); shift
  for ((i = 0; i < n; i++)); do "$@" >/dev/null 2>&1 && return 0; sleep 0.2; done
  echo "timed out waiting for: $*"; return 1
}

# munge with its own key and socket.
mkdir -m 711 "$tmp/munge"
head -c 1024 /dev/urandom > "$tmp/munge/munge.key"; chmod 400 "$tmp/munge/munge.key"
munged --foreground --force --socket="$tmp/munge/socket" --key-file="$tmp/munge/munge.key" \
  --pid-file="$tmp/munge/pid" --seed-file="$tmp/munge/seed" --log-file="$tmp/munged.log" > "$tmp/munged.stdout.log" 2>&1 &
pids+=($!)
wait_for 10 test -S "$tmp/munge/socket"

# A one-node cluster: this host with 2 CPUs.
node=$(hostname -s)
mkdir -p "$tmp/state" "$tmp/spool"
cat > "$tmp/slurm.conf" <<CONF
ClusterName=fabatlastest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$tmp/munge/socket
CredType=cred/munge
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
InactiveLimit=0
MinJobAge=300
NodeName=$node NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN
PartitionName=debug Nodes=$node Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$tmp/slurm.conf
slurmctld -D -i -f "$SLURM_CONF" > "$tmp/slurmctld.stdout.log" 2>&1 &
pids+=($!)
wait_for 20 scontrol ping
slurmd -D -f "$SLURM_CONF" -N "$node" > "$tmp/slurmd.stdout.log" 2>&1 &
pids+=($!)
wait_for 30 bash -c '[[ $(sinfo -h -n '"$node"' -o %t) == idle ]]'
echo "slurm: node $node idle"

# The coordinator: TLS from ops/tls/make-certs.sh and a bearer token.
bash "$src/ops/tls/make-certs.sh" "$tmp/tls" localhost >/dev/null
"$bin/fabatlas-coordinator" --listen 127.0.0.1:0 --state-dir "$tmp/coordinator" --port-file "$tmp/port" \
  --tls-cert "$tmp/tls/server.pem" --tls-key "$tmp/tls/server.key" --token-file "$tmp/tls/token" \
  --log-format json > "$tmp/coordinator.log" 2>&1 &
pids+=($!)
wait_for 20 test -s "$tmp/port"
coordinator=localhost:$(cat "$tmp/port")

# The batch script as an operator submits it (workers from PATH).
cd "$tmp"
job=$(PATH="$bin:$PATH" COORDINATOR=$coordinator FABATLAS_TOKEN_FILE=$tmp/tls/token FABATLAS_TLS_CA=$tmp/tls/ca.pem \
  sbatch --parsable --nodes=1 --cpus-per-task=2 --output="$tmp/slurm-%j.out" "$src/ops/slurm/fabatlas-workers.sbatch")
echo "slurm: batch job $job"
export FABATLAS_TOKEN=$(cat "$tmp/tls/token")
id=$("$bin/fabatlas" submit "$src/tests/cluster/data/tube_small.yaml" --coordinator "$coordinator" \
  --tls-ca "$tmp/tls/ca.pem" | awk '{print $1}')
"$bin/fabatlas" watch "$id" --coordinator "$coordinator" --tls-ca "$tmp/tls/ca.pem" > "$tmp/watch.log" 2>&1
tail -n 1 "$tmp/watch.log"
grep -q SUCCEEDED "$tmp/watch.log"
# The workers that did the job were the Slurm ones (slot count = the
# allocation's CPUs, passed to srun explicitly).
grep -q '"event":"worker_joined".*"slots":2' "$tmp/coordinator.log"

# Drain: SIGTERM to the job's steps; the workers return their leases and
# exit 0, so the batch script and the Slurm job complete.
scancel --signal=TERM "$job"
wait_for 60 bash -c '[[ ! $(scontrol show job '"$job"' | grep -o "JobState=[A-Z]*") =~ ^JobState=(PENDING|RUNNING|COMPLETING)$ ]]'
state=$(scontrol show job "$job" | grep -o 'JobState=[A-Z]* ' | head -n 1)
code=$(scontrol show job "$job" | grep -o ' ExitCode=[0-9:]*' | head -n 1)
echo "slurm: batch job $job$state$code"
[[ $state == "JobState=COMPLETED " && $code == " ExitCode=0:0" ]]
grep -q '"event":"worker_exit"' "$tmp"/slurm-"$job".out
echo "slurm test passed: fabatlas job $id on Slurm batch job $job"
