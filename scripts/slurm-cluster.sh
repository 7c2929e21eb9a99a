#!/usr/bin/env bash
# A private Slurm cluster on this machine, for the reconstruction's Slurm executor and its tests
# (reconstruction/src/auv/recon/pipeline/README.md, "Slurm"): munge, slurmctld and N slurmd
# "hosts". slurmctld and each slurmd run in a network namespace of their own, joined by a bridge
# in this one: Slurm's daemons listen on every address they have, which in a namespace is the
# bridge's subnet only. (Not on loopback alone: in a namespace with only lo, Slurm 22.05 cannot
# resolve a listening address.) Everything lives in one folder; nothing in /etc is read or
# changed. Slurm and munge are Debian's
# (scripts/install-deps.sh). Needs root (namespaces, daemons).
#
#   scripts/slurm-cluster.sh up [--dir DIR] [--nodes N] [--cpus-per-node C] [--mem-per-node MB]
#                               [--subnet A.B.C] [--port P] [--hide DIR]
#   scripts/slurm-cluster.sh down [--dir DIR]
#   scripts/slurm-cluster.sh status [--dir DIR]
#
#   --dir            the cluster's folder (default /tmp/auv-slurm): slurm.conf, env.sh, logs, state
#   --nodes          slurmd hosts (default 2), named n1..nN, partition "survey"
#   --cpus-per-node  CPUs each host offers (default 1: two hosts share this machine's two cores)
#   --mem-per-node   MB each host offers to --mem (default 2048)
#   --subnet         the bridge's /24 (default 10.213.0): this namespace .1, host i .(i+1),
#                    the controller .254
#   --port           slurmctld's port, slurmd's is the next (default 16817)
#   --hide           the hosts see an empty DIR (a tmpfs over it, as a node's local disk sees
#                    none of the submitting machine's files): for tests of what they cannot see
#
# After `up`: `source DIR/env.sh` points sbatch, squeue, scancel, sinfo at the cluster.
set -euo pipefail

die() { echo "slurm-cluster: $*" >&2; exit 1; }

command=${1:-}
[ -n "$command" ] || die "expected up, down or status (see the file's comment)"
shift
dir=/tmp/auv-slurm nodes=2 cpus=1 mem=2048 subnet=10.213.0 port=16817 hide=""
while [ $# -gt 0 ]; do
  case "$1" in
    --dir) dir="${2:?--dir needs a folder}"; shift ;;
    --nodes) nodes="${2:?--nodes needs a number}"; shift ;;
    --cpus-per-node) cpus="${2:?--cpus-per-node needs a number}"; shift ;;
    --mem-per-node) mem="${2:?--mem-per-node needs MB}"; shift ;;
    --subnet) subnet="${2:?--subnet needs A.B.C}"; shift ;;
    --port) port="${2:?--port needs a number}"; shift ;;
    --hide) hide="${2:?--hide needs a folder}"; shift ;;
    *) die "unknown argument '$1'" ;;
  esac
  shift
done
for value in "$nodes" "$cpus" "$mem" "$port"; do
  [[ "$value" =~ ^[1-9][0-9]*$ ]] || die "'$value' is not a positive whole number"
done
[[ "$subnet" =~ ^[0-9]+\.[0-9]+\.[0-9]+$ ]] || die "--subnet '$subnet': expected A.B.C"
[ "$nodes" -le 200 ] || die "--nodes $nodes: at most 200"
dir=$(realpath -m "$dir")
conf="$dir/slurm.conf"
# Names derived from the folder, so two clusters in two folders do not meet.
tag=$(printf '%s' "$dir" | md5sum | cut -c1-6)
bridge="auvs$tag"

namespace() { echo "auvs$tag-$1"; }  # $1: n<i> or c (the controller)

stop_pid_file() {
  local file=$1
  [ -f "$file" ] || return 0
  local pid
  pid=$(cat "$file")
  if kill -0 "$pid" 2>/dev/null; then
    kill "$pid" 2>/dev/null || true
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  fi
  rm -f "$file"
}

down() {
  [ -d "$dir" ] || { echo "slurm-cluster: no cluster in $dir"; return 0; }
  for file in "$dir"/n*/slurmd.pid "$dir/slurmctld.pid" "$dir/munged.pid"; do
    stop_pid_file "$file"
  done
  for ns in $(ip netns list 2>/dev/null | awk '{print $1}' | grep "^auvs$tag-" || true); do
    ip netns delete "$ns"
  done
  ip link show "$bridge" >/dev/null 2>&1 && ip link delete "$bridge"
  rm -f "$dir/env.sh"
  echo "slurm-cluster: down ($dir)"
}

status() {
  [ -f "$dir/env.sh" ] || die "no cluster is up in $dir"
  # shellcheck disable=SC1091
  source "$dir/env.sh"
  sinfo --Node --format="%N %T %c %m"
  squeue --format="%i %j %T %R"
}

write_conf() {
  local control_addr=$1 host
  host=$(hostname -s)
  {
    echo "# Written by scripts/slurm-cluster.sh; the cluster's whole configuration."
    echo "ClusterName=auv"
    echo "SlurmctldHost=$host($control_addr)"
    echo "SlurmctldPort=$port"
    echo "SlurmdPort=$((port + 1))"
    echo "SlurmUser=root"
    echo "AuthType=auth/munge"
    echo "CredType=cred/munge"
    echo "AuthInfo=socket=$dir/munge/munge.socket"
    echo "StateSaveLocation=$dir/state"
    echo "SlurmctldPidFile=$dir/slurmctld.pid"
    echo "SlurmctldLogFile=$dir/slurmctld.log"
    echo "SlurmdSpoolDir=$dir/%n/spool"
    echo "SlurmdPidFile=$dir/%n/slurmd.pid"
    echo "SlurmdLogFile=$dir/%n/slurmd.log"
    echo "PlugStackConfig=$dir/plugstack.conf"
    # No cgroups: the hosts share one kernel and may run in a container.
    echo "ProctrackType=proctrack/linuxproc"
    echo "TaskPlugin=task/none"
    echo "JobAcctGatherType=jobacct_gather/none"
    echo "AccountingStorageType=accounting_storage/none"
    echo "JobCompType=jobcomp/none"
    echo "MpiDefault=none"
    echo "SchedulerType=sched/backfill"
    echo "SelectType=select/cons_tres"
    echo "SelectTypeParameters=CR_Core_Memory"
    echo "ReturnToService=2"
    echo "SlurmdTimeout=60"
    # Finished jobs stay visible to squeue/scontrol for an hour (no accounting database).
    echo "MinJobAge=3600"
    for i in $(seq "$nodes"); do
      echo "NodeName=n$i NodeAddr=$subnet.$((i + 1)) CPUs=$cpus RealMemory=$mem State=UNKNOWN"
    done
    echo "PartitionName=survey Nodes=ALL Default=YES MaxTime=INFINITE State=UP"
  } > "$conf"
}

# A network namespace for host $1 at address $2, on the bridge.
host_namespace() {
  local ns
  ns=$(namespace "$1")
  ip netns add "$ns"
  ip link add "v$tag$1" type veth peer name eth0 netns "$ns"
  ip link set "v$tag$1" master "$bridge" up
  ip netns exec "$ns" ip link set lo up
  ip netns exec "$ns" ip addr add "$2/24" dev eth0
  ip netns exec "$ns" ip link set eth0 up
}

# Starts daemon "$@" in host $1's namespace. nsenter, not `ip netns exec`: that remounts /sys,
# hiding the cgroup mounts slurmd needs.
run_in() {
  local ns
  ns=$(namespace "$1")
  shift
  nsenter --net="/var/run/netns/$ns" "$@" </dev/null >/dev/null 2>&1
}

up() {
  [ "$(id -u)" -eq 0 ] || die "needs root (network namespaces and the daemons)"
  for tool in munged slurmctld slurmd sbatch; do
    command -v "$tool" >/dev/null || die "$tool not found (scripts/install-deps.sh installs slurm and munge)"
  done
  [ ! -f "$dir/env.sh" ] || die "a cluster is already up in $dir (scripts/slurm-cluster.sh down --dir $dir)"
  mkdir -p "$dir/munge" "$dir/state"
  chmod 700 "$dir/munge"
  : > "$dir/plugstack.conf"
  # A key of this cluster's own.
  [ -f "$dir/munge/munge.key" ] || head -c 1024 /dev/urandom > "$dir/munge/munge.key"
  chmod 400 "$dir/munge/munge.key"
  munged --force --socket="$dir/munge/munge.socket" --key-file="$dir/munge/munge.key" \
    --pid-file="$dir/munged.pid" --log-file="$dir/munged.log" --seed-file="$dir/munge/seed" \
    </dev/null >/dev/null 2>&1

  ip link add "$bridge" type bridge
  ip addr add "$subnet.1/24" dev "$bridge"
  ip link set "$bridge" up
  write_conf "$subnet.254"
  host_namespace c "$subnet.254"
  run_in c slurmctld -f "$conf"
  for i in $(seq "$nodes"); do
    mkdir -p "$dir/n$i/spool"
    host_namespace "n$i" "$subnet.$((i + 1))"
    if [ -n "$hide" ]; then
      mkdir -p "$hide"
      run_in "n$i" unshare --mount --propagation private sh -c \
        'mount -t tmpfs tmpfs "$1" && shift && exec "$@"' sh "$hide" slurmd -f "$conf" -N "n$i"
    else
      run_in "n$i" slurmd -f "$conf" -N "n$i"
    fi
  done
  echo "export SLURM_CONF=$conf" > "$dir/env.sh"
  # Ready when every host is idle.
  export SLURM_CONF=$conf
  local deadline=$((SECONDS + 60)) idle
  while [ $SECONDS -lt $deadline ]; do
    idle=$(timeout 10 sinfo --noheader --Node --states=idle --format=%N 2>/dev/null |
      sort -u | grep -c . || true)
    if [ "$idle" -eq "$nodes" ]; then
      echo "slurm-cluster: up, $nodes host(s) idle; source $dir/env.sh"
      return 0
    fi
    sleep 0.5
  done
  sinfo --Node >&2 || true
  die "the hosts did not come up within 60 s (logs in $dir)"
}

case "$command" in
  up)
    trap 'status=$?; [ $status -eq 0 ] || down; exit $status' EXIT
    up
    trap - EXIT
    ;;
  down) down ;;
  status) status ;;
  *) die "unknown command '$command' (up, down, status)" ;;
esac
