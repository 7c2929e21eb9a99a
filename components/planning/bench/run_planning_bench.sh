#!/usr/bin/env bash
# Runs the planning benchmarks (bench/README.md) and writes bench_results/planner_bench_<stamp>.md,
# update_bench_<stamp>.md (+ .csv) and oracle_<stamp>.md. Usage, after a build:
#   components/planning/bench/run_planning_bench.sh [--quick] [--seeds N] [--queries all]
#                                                   [--3d] [--install DIR]
# The world maps come from `auv sim octomap` (worlds breakwater, canyon, dead_end_bay, seed 1):
# 0.5 m for the planners (the mapping component's resolution), 0.1 m for the oracle.
set -euo pipefail
script=$(readlink -f "$0")
cd "$(dirname "$script")/../../.."
install_dir=install
planner_args=(--queries first)
update_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) planner_args+=(--quick); update_args+=(--quick) ;;
    --seeds) planner_args+=(--seeds "$2"); shift ;;
    --queries) planner_args+=(--queries "$2"); shift ;;
    --3d) planner_args+=(--3d); update_args+=(--3d) ;;
    --install) install_dir="$2"; shift ;;
    -h|--help) sed -n '2,7p' "$script"; exit 0 ;;
    *) echo "run_planning_bench: unknown argument '$1' (--help)" >&2; exit 2 ;;
  esac
  shift
done
set +u; source install/setup.bash; [ "$install_dir" = install ] || source "$install_dir/setup.bash"; set -u
bin="$install_dir/lib/auv_planning"
sim_tool="$install_dir/bin/auv-sim"  # what `auv sim` runs
for program in "$bin/planner_bench" "$bin/update_bench" "$bin/planning_oracle" "$sim_tool"; do
  [ -x "$program" ] || { echo "run_planning_bench: $program not built" >&2; exit 1; }
done
stamp=$(date +%Y%m%d_%H%M%S)
maps="bench_results/planning_maps"
mkdir -p bench_results "$maps"
started=$SECONDS

pairs=()
for world in breakwater canyon dead_end_bay; do
  output=$("$sim_tool" octomap "$world" --seed 1 --resolution 0.5 --out "$maps/$world-0.5.bt")
  echo "$output"
  scenario=$(awk '$1 == "scenario" { print $2 }' <<<"$output")
  "$sim_tool" octomap "$world" --seed 1 --resolution 0.1 --out "$maps/$world-0.1.bt" | tail -n 1
  pairs+=("$scenario" "$maps/$world-0.5.bt")
done

"$bin/planner_bench" "${planner_args[@]}" --out "bench_results/planner_bench_$stamp.md" \
  "${pairs[@]}"
"$bin/update_bench" "${update_args[@]}" --out "bench_results/update_bench_$stamp.md" \
  "${pairs[2]}" "${pairs[3]}"

# The oracle on the true 0.1 m maps: the shortest path of each world's first query at the
# planner's clearance (the reference for executed path lengths).
oracle="bench_results/oracle_$stamp.md"
{
  echo "# Shortest paths (oracle) $stamp"
  echo
  echo "First query of each world on its true 0.1 m map, fixed depth, at the planning component's"
  echo "clearance (hull_radius + safety_margin defaults), grid 0.1 m."
  echo
  echo "| world | start | goal | oracle length (m) |"
  echo "|---|---|---|---:|"
} >"$oracle"
for index in 0 1 2; do
  world=$(basename "${pairs[$((2 * index + 1))]}" -0.5.bt)
  scenario=${pairs[$((2 * index))]}
  # Generated scenarios write `position: [x, y, z]` and `goal: [x, y, z]` on one line each.
  start=$(sed -n 's/.*position: \[\([^]]*\)\].*/\1/p' "$scenario" | head -n 1 | tr -d ' ')
  goal=$(sed -n 's/.*goal: \[\([^]]*\)\].*/\1/p' "$scenario" | head -n 1 | tr -d ' ')
  length=$("$bin/planning_oracle" --map "$maps/$world-0.1.bt" --start "$start" --goal "$goal" \
    --clearance planner --fixed-depth --grid 0.1 --quiet || echo "none")
  echo "| $world | $start | $goal | $length |" >>"$oracle"
done
cat "$oracle"
# Which OnlineRRTstar was measured (it changes often): its source's checksum and date.
core=components/planning/src/auv/planning/online_rrt_star.cc
note="OnlineRRTstar source measured: $core md5 $(md5sum "$core" | cut -c1-12), modified $(date -r "$core" '+%Y-%m-%d %H:%M')."
for file in "bench_results/planner_bench_$stamp.md" "bench_results/update_bench_$stamp.md"; do
  printf '\n%s\n' "$note" >>"$file"
done
echo "planning benchmarks: $((SECONDS - started)) s; results bench_results/*_$stamp.*"
