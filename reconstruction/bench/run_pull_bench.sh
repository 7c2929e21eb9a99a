#!/usr/bin/env bash
# Runs the pull benchmark on loopback (DDS domains 5 and 6) and writes the table to
# bench_results/pull_bench_<time>.md in the workspace (not committed). Extra arguments go to
# pull_bench (e.g. --files 4 --file-mb 32 --runs 3 --root auv_runs/demo-canyon/vehicle/recordings).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
workspace="${AUV_WORKSPACE:-$(pwd)}"
# pull_bench installs into lib/auv_reconstruction/ (not on PATH): the workspace's install, else
# PATH, else next to this script (a plain CMake build).
bench="$here/../../install/lib/auv_reconstruction/pull_bench"
[ -x "$bench" ] || bench="$(command -v pull_bench || true)"
[ -z "$bench" ] && [ -x "$here/pull_bench" ] && bench="$here/pull_bench"
if [ -z "$bench" ]; then echo "run_pull_bench: pull_bench not built (./scripts/build.sh)" >&2; exit 1; fi
# The vehicle is `auv run recorder` (pull_bench starts it per vendor pairing).
command -v auv >/dev/null || { echo "run_pull_bench: auv not on PATH (source install/setup.bash)" >&2; exit 1; }
mkdir -p "$workspace/bench_results"
out="$workspace/bench_results/pull_bench_$(date +%Y%m%d_%H%M%S).md"
"$bench" --out "$out" "$@"
