#!/usr/bin/env bash
# Mapping benchmark: beams/s and points/s inserted through the mapping component (both DDS
# vendors, in the bench process and in its own process) and through MapBuilder, beside raw
# OcTree::insertPointCloud on the same data in the same run (components/mapping/README.md,
# "Benchmark"). Runs mapping_bench --runs times (default 3; the machine is shared, one run says
# little), writes bench_results/mapping_bench_<stamp>.md (every run's tables, then a summary
# with the median ratio per row) and .log, and prints the summary.
#
# Usage (from anywhere, after a build): components/mapping/bench/run_mapping_bench.sh
#          [--runs N] [--install DIR] [mapping_bench options, e.g. --beams 100000 --pin]
# --install: the install prefix holding lib/auv_mapping/mapping_bench (default: the
# workspace's install/). DDS stays on loopback (the layer's default configuration; any
# CYCLONEDDS_URI / FASTRTPS_DEFAULT_PROFILES_FILE is unset). Domains 86-89 (test/README.md).
set -euo pipefail

WS="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
INSTALL="$WS/install"
RUNS=3
ARGS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --runs) RUNS="$2"; shift ;;
    --install) INSTALL="$(cd "$2" && pwd)"; shift ;;
    -h|--help) sed -n '2,13p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) ARGS+=("$1") ;;
  esac
  shift
done

bench="$INSTALL/lib/auv_mapping/mapping_bench"
[ -x "$bench" ] || { echo "run_mapping_bench: $bench not built (./scripts/build.sh)" >&2; exit 1; }
set +u
source "$WS/install/setup.bash"
# A separate prefix (a scratch build) goes in front, so its libraries win.
[ "$INSTALL" = "$WS/install" ] || source "$INSTALL/setup.bash"
set -u
unset CYCLONEDDS_URI FASTRTPS_DEFAULT_PROFILES_FILE AUV_DDS AUV_DOMAIN_ID

mkdir -p "$WS/bench_results"
stamp="$(date +%Y%m%d_%H%M%S)"
out="$WS/bench_results/mapping_bench_$stamp.md"
log="$WS/bench_results/mapping_bench_$stamp.log"
runs_md=()
{
  echo "# Mapping benchmark $stamp"
  echo
  echo "$(nproc) CPUs ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')),"
  echo "load average at start: $(cut -d' ' -f1-3 /proc/loadavg); options: ${ARGS[*]:-(defaults)}"
  echo
} > "$out"
for run in $(seq 1 "$RUNS"); do
  echo "run_mapping_bench: run $run of $RUNS (log: $log)" >&2
  md="$WS/bench_results/mapping_bench_${stamp}_run$run.md"
  echo "=== run $run, load $(cut -d' ' -f1-3 /proc/loadavg)" >> "$log"
  "$bench" --out "$md" "${ARGS[@]}" >> "$log" 2>&1 ||
    { echo "run_mapping_bench: mapping_bench failed, see $log" >&2; exit 1; }
  runs_md+=("$md")
  { echo "## Run $run (load average after: $(cut -d' ' -f1-3 /proc/loadavg))"; echo
    sed -e '1,/^$/d' -e 's/^## /### /' "$md"; echo; } >> "$out"
done

# Summary: per table and row, the ratios of every run and their median.
python3 - "${runs_md[@]}" >> "$out" <<'EOF'
import re, statistics, sys
rows = {}  # (table, path) -> [(ratio, cpu_ratio, same_map)]
order = []
for path in sys.argv[1:]:
    table = None
    for line in open(path):
        if line.startswith("## "):
            table = line[3:].split(" (")[0].strip()
        # path | /s | raw /s | ratio | CPU | raw CPU | CPU ratio | process CPU | same map | notes
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if table is None or len(cells) < 10 or cells[0] in ("path", "---"):
            continue
        key = (table, cells[0])
        if key not in rows:
            rows[key] = []
            order.append(key)
        if re.match(r"^[\d.]+$", cells[3]):
            rows[key].append((float(cells[3]), float(cells[6]), cells[8]))
        else:  # failed: the note says why
            rows[key].append((None, None, cells[9]))
runs = len(sys.argv) - 1
print(f"## Summary over {runs} run(s)\n")
print("ratio = rate / raw OcTree::insertPointCloud's, measured just before; CPU ratio = raw CPU "
      "time per measurement / the inserting thread's (see the tables). Goal: ratio >= 0.9.\n")
for table in dict.fromkeys(t for t, _ in order):
    print(f"### {table}\n")
    print("| path | ratio per run | median ratio | CPU ratio per run | median CPU ratio | same map |")
    print("|---|---|---:|---|---:|---|")
    for key in order:
        if key[0] != table:
            continue
        r = rows[key]
        ok = [x for x in r if x[0] is not None]
        fmt = lambda v: "failed" if v is None else f"{v:.2f}"
        median = lambda i: f"{statistics.median(x[i] for x in ok):.2f}" if ok else "-"
        same = "yes" if all(x[2].startswith("yes") for x in ok) else "NO"
        if len(ok) < len(r):
            same += f" ({len(r) - len(ok)} failed: {next(x[2] for x in r if x[0] is None)})"
        print(f"| {key[1]} | {', '.join(fmt(x[0]) for x in r)} | {median(0)} | "
              f"{', '.join(fmt(x[1]) for x in r)} | {median(1)} | {same} |")
    print()
EOF
echo "load average at end: $(cut -d' ' -f1-3 /proc/loadavg)" >> "$out"
rm -f "${runs_md[@]}"
sed -n '/^## Summary/,$p' "$out"
echo "run_mapping_bench: wrote $out" >&2
