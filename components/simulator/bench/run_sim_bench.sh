#!/usr/bin/env bash
# Runs the simulator benchmark (it pins itself to one core for the per-core figures) and writes
# bench_results/sim_bench_<stamp>.md. Usage (from the workspace root, after a build):
#   components/simulator/bench/run_sim_bench.sh [sim_bench options, e.g. --world breakwater]
set -euo pipefail
cd "$(dirname "$0")/../../.."
set +u; source install/setup.bash; set -u
bench=install/lib/auv_simulator/sim_bench
[ -x "$bench" ] || { echo "run_sim_bench: $bench not built (./scripts/build.sh)" >&2; exit 1; }
mkdir -p bench_results
out="bench_results/sim_bench_$(date +%Y%m%d_%H%M%S).md"
"$bench" --out "$out" "$@"
