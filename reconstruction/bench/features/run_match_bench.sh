#!/usr/bin/env bash
# Matching before and after (issue 24), in one run on one survey: `match` of an earlier build
# (--before: its `auv-recon` binary, e.g. one built from the commit before the change) and of
# this workspace's, each followed by the same `auv recon sfm` and `auv recon evaluate` (this
# workspace's), so the registered images and the camera error compare the matches alone.
#
#   reconstruction/bench/features/run_match_bench.sh --survey S --before BIN
#       [--threads N] [--out bench_results] [--sides before,after] [-- MATCH OPTIONS...]
#
# The survey needs features/ (`auv recon features`) and simulation.json (a simulated survey:
# reconstruction/bench/pipeline/make_canyon_survey.sh). Its features/matches/, sparse/ and
# evaluation.json are rewritten; each side's copies stay in bench_results/match_bench_<time>/.
# Writes bench_results/match_bench_<time>.json and .md: wall s and peak MiB of each match,
# candidate pairs by status, verified pairs and matches, registered images, camera position
# error, the time ratio after / before and the machine's load at each start.
set -euo pipefail
cd "$(dirname "$0")/../../.."
survey=
before=
threads=2
out=bench_results
sides=before,after
match_options=()
while [ $# -gt 0 ]; do
  case "$1" in
    --survey) survey=$2; shift 2 ;;
    --before) before=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --sides) sides=$2; shift 2 ;;
    --) shift; match_options=("$@"); break ;;
    -h|--help) sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "run_match_bench: unknown option $1 (--help)" >&2; exit 2 ;;
  esac
done
[ -n "$survey" ] || { echo "run_match_bench: --survey is required" >&2; exit 2; }
[ -f "$survey/features/index.csv" ] ||
  { echo "run_match_bench: $survey/features/index.csv missing: run auv recon features first" >&2; exit 2; }
case ",$sides," in *,before,*)
  [ -x "$before" ] || { echo "run_match_bench: --before must name an auv-recon binary" >&2; exit 2; } ;;
esac
set +u; source install/setup.bash; set -u
stamp=$(date +%Y%m%d_%H%M%S)
work="$out/match_bench_$stamp"
mkdir -p "$work"
echo "run_match_bench: $survey, sides $sides, $threads threads -> $work"

for side in ${sides//,/ }; do
  case "$side" in
    before) tool=$before ;;
    after) tool=auv-recon ;;
    *) echo "run_match_bench: unknown side $side (before, after)" >&2; exit 2 ;;
  esac
  mkdir -p "$work/$side"
  cut -d' ' -f1 /proc/loadavg > "$work/$side/load"
  echo "== $side: $tool match $survey --threads $threads ${match_options[*]:-}"
  /usr/bin/time -f "%e %M" -o "$work/$side/match.time" \
    "$tool" match "$survey" --threads "$threads" "${match_options[@]}" > "$work/$side/match.log" 2>&1
  tail -1 "$work/$side/match.log"
  cp -r "$survey/features/matches" "$work/$side/matches"
  echo "== $side: auv recon sfm, evaluate"
  /usr/bin/time -f "%e %M" -o "$work/$side/sfm.time" \
    auv recon sfm "$survey" --threads "$threads" > "$work/$side/sfm.log" 2>&1
  cp -r "$survey/sparse" "$work/$side/sparse"
  auv recon evaluate "$survey" > "$work/$side/evaluate.log" 2>&1 || true
  cp "$survey/evaluation.json" "$work/$side/evaluation.json" 2>/dev/null || true
done

python3 - "$work" "$survey" "$sides" <<'EOF'
import collections, csv, json, os, sys
work, survey, sides = sys.argv[1], sys.argv[2], sys.argv[3].split(",")
result = {"survey": survey, "sides": {}}
for side in sides:
    d = os.path.join(work, side)
    seconds, kib = open(os.path.join(d, "match.time")).read().split()[-2:]
    rows = list(csv.DictReader(open(os.path.join(d, "matches", "pairs.csv"))))
    status = collections.Counter(r["status"] for r in rows)
    verified = [r for r in rows if r["status"] == "verified"]
    figures = {
        "match_seconds": float(seconds), "match_peak_mib": int(kib) // 1024,
        "load_at_start": float(open(os.path.join(d, "load")).read()),
        "candidate_pairs": len(rows), "status": dict(status),
        "verified_pairs": len(verified),
        "verified_matches": sum(int(r["inliers"]) for r in verified),
        "sfm_seconds": float(open(os.path.join(d, "sfm.time")).read().split()[-2]),
    }
    if rows and "iterations" in rows[0]:
        figures["ransac_samples"] = sum(int(r["iterations"]) for r in rows)
    try:
        e = json.load(open(os.path.join(d, "evaluation.json")))
        figures["images_registered"] = e["images"]["registered"]
        figures["keyframes"] = e["images"]["keyframes"]
        figures["camera_position_error_m"] = e["camera_error"]["position_m"]
    except (OSError, KeyError, ValueError):
        figures["evaluation"] = "missing (see evaluate.log)"
    result["sides"][side] = figures
s = result["sides"]
if "before" in s and "after" in s:
    result["match_time_ratio_after_over_before"] = s["after"]["match_seconds"] / s["before"]["match_seconds"]
json.dump(result, open(work + ".json", "w"), indent=2)
with open(work + ".md", "w") as md:
    md.write(f"# match before / after on {survey}\n\n| figure | " + " | ".join(sides) + " |\n|---|" + "---:|" * len(sides) + "\n")
    keys = ["match_seconds", "match_peak_mib", "load_at_start", "candidate_pairs", "verified_pairs",
            "verified_matches", "ransac_samples", "images_registered", "keyframes", "sfm_seconds"]
    for k in keys:
        md.write(f"| {k} | " + " | ".join(str(s[x].get(k, "")) for x in sides) + " |\n")
    md.write("| camera error median / max mm | " + " | ".join(
        "%.1f / %.1f" % (1000 * s[x]["camera_position_error_m"]["median"], 1000 * s[x]["camera_position_error_m"]["max"])
        if "camera_position_error_m" in s[x] else "" for x in sides) + " |\n")
    md.write("| status | " + " | ".join(json.dumps(s[x]["status"]) for x in sides) + " |\n")
    if "match_time_ratio_after_over_before" in result:
        md.write(f"\nmatch time after / before: **{result['match_time_ratio_after_over_before']:.3f}** (goal <= 0.25)\n")
print(open(work + ".md").read())
print("results:", work + ".json")
EOF
