#!/usr/bin/env bash
# Slurm's overhead per job (issue 24), on a private cluster of Debian's Slurm
# (scripts/slurm-cluster.sh: slurmctld and N slurmd hosts in network namespaces on this machine),
# with jobs that do nothing, so everything measured is the scheduler's:
#
#   * chain: N jobs, each `afterok` on the one before (how `auv recon run --executor slurm`
#     chains its stages): wall time from the first sbatch to the last job's end, / N;
#   * array: one job array of N tasks (how a sharded stage runs): wall time / N;
#   * anchor, in the same run: the same N job bodies run one after the other on this machine.
#
#   reconstruction/bench/cluster/run_slurm_overhead.sh [--jobs N] [--nodes H] [--out bench_results]
#
# Needs root (namespaces, daemons). Brings its own cluster up in /tmp/auv-slurm-bench (port
# 16837, subnet 10.213.7) and down again. Writes bench_results/slurm_overhead_<time>.json.
set -euo pipefail
cd "$(dirname "$0")/../../.."
jobs=20
nodes=2
out=bench_results
while [ $# -gt 0 ]; do
  case "$1" in
    --jobs) jobs=$2; shift 2 ;;
    --nodes) nodes=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    -h|--help) sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "run_slurm_overhead: unknown option $1 (--help)" >&2; exit 2 ;;
  esac
done
dir=/tmp/auv-slurm-bench
work=$(mktemp -d)
cleanup() { scripts/slurm-cluster.sh down --dir "$dir" > /dev/null 2>&1 || true; rm -rf "$work"; }
trap cleanup EXIT
scripts/slurm-cluster.sh up --dir "$dir" --nodes "$nodes" --port 16837 --subnet 10.213.7 \
  > "$work/up.log" 2>&1 || { cat "$work/up.log" >&2; exit 1; }
# shellcheck disable=SC1091
source "$dir/env.sh"
now() { date +%s.%N; }
# Waits until none of the given jobs is pending or running any more.
wait_gone() {
  while squeue -h -j "$1" -t PENDING,RUNNING,CONFIGURING,COMPLETING 2>/dev/null | grep -q .; do
    sleep 0.05
  done
}
printf '#!/bin/sh\ntrue\n' > "$work/job.sh"

# Anchor: the bodies alone.
t0=$(now)
for _ in $(seq "$jobs"); do sh "$work/job.sh"; done
anchor=$(python3 -c "print($(now) - $t0)")

# Chain.
t0=$(now)
previous=
ids=
for _ in $(seq "$jobs"); do
  previous=$(sbatch --parsable --chdir "$work" --output /dev/null \
    ${previous:+--dependency=afterok:$previous --kill-on-invalid-dep=yes} "$work/job.sh")
  ids="${ids:+$ids,}$previous"
done
submitted=$(python3 -c "print($(now) - $t0)")
wait_gone "$ids"
chain=$(python3 -c "print($(now) - $t0)")
failed=$(scontrol --oneliner show job "$previous" | grep -o 'JobState=[A-Z]*')

# Array.
t0=$(now)
array=$(sbatch --parsable --chdir "$work" --output /dev/null --array "0-$((jobs - 1))" "$work/job.sh")
wait_gone "$array"
array_s=$(python3 -c "print($(now) - $t0)")

stamp=$(date +%Y%m%d_%H%M%S)
mkdir -p "$out"
python3 - "$out/slurm_overhead_$stamp.json" "$jobs" "$nodes" "$anchor" "$submitted" "$chain" \
  "$array_s" "$failed" "$(sbatch --version)" <<'EOF'
import json, sys
path, jobs, nodes, anchor, submitted, chain, array, last, version = sys.argv[1:10]
jobs = int(jobs)
r = {"jobs": jobs, "hosts": int(nodes), "slurm": version, "last_chain_job": last,
     "anchor_local_s_per_job": float(anchor) / jobs,
     "chain_submit_s_per_job": float(submitted) / jobs,
     "chain_s_per_job": float(chain) / jobs,
     "array_s_per_task": float(array) / jobs}
json.dump(r, open(path, "w"), indent=2)
print(json.dumps(r, indent=2))
print("results:", path)
EOF
