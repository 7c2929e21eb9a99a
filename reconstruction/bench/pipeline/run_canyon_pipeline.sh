#!/usr/bin/env bash
# The whole reconstruction of the simulated canyon survey (benchmark, not a test; issue 7's
# figures): every stage from the pulled videos to the textured model, each timed with its peak
# memory (GNU time), then `auv recon evaluate` (F-scores at 5 and 10 cm of the dense cloud and
# the mesh in the well-imaged region, camera position error, texture PSNR) and `auv recon
# figures`. Results: bench_results/canyon_pipeline_<time>.md and .json.
#
#   reconstruction/bench/pipeline/run_canyon_pipeline.sh [--survey DIR] [--make [ARGS...]]
#       [--from STAGE] [--stages a,b,c]
#
# --survey   the survey folder (default auv_runs/survey-canyon-eval, made by
#            make_canyon_survey.sh; --make runs that first, with the remaining arguments)
# --from     start at this stage (earlier outputs kept); --stages: only these
# The machine is shared: timings are noisy (the load average is recorded next to them).
set -euo pipefail
cd "$(dirname "$0")/../../.."
survey=auv_runs/survey-canyon-eval
from=""
only=""
make=0
make_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --survey) survey=$2; shift 2 ;;
    --from) from=$2; shift 2 ;;
    --stages) only=$2; shift 2 ;;
    --make) make=1; shift; make_args=("$@"); break ;;
    -h|--help) sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "run_canyon_pipeline: unknown option $1 (--help)" >&2; exit 2 ;;
  esac
done
set +u; source install/setup.bash; set -u
if [ "$make" = 1 ]; then
  reconstruction/bench/pipeline/make_canyon_survey.sh --survey "$survey" "${make_args[@]}"
fi
[ -f "$survey/simulation.json" ] || {
  echo "run_canyon_pipeline: $survey/simulation.json not found (make_canyon_survey.sh first)" >&2
  exit 1
}
stamp=$(date +%Y%m%d_%H%M%S)
mkdir -p bench_results
results=bench_results/canyon_pipeline_$stamp
rows=$results.rows
: > "$rows"

stages=(keyframes correct features match sfm dense mesh restore texture evaluate figures)
started=0
[ -z "$from" ] && started=1
status=0
for stage in "${stages[@]}"; do
  [ "$stage" = "$from" ] && started=1
  [ "$started" = 1 ] || continue
  if [ -n "$only" ] && [[ ",$only," != *",$stage,"* ]]; then continue; fi
  load=$(cut -d' ' -f1 /proc/loadavg)
  printf '\n\033[1m== auv recon %s %s\033[0m (load %s)\n' "$stage" "$survey" "$load"
  log=$results.$stage.log
  if /usr/bin/time -f '%e %M' -o "$results.time" auv recon "$stage" "$survey" 2>&1 | tee "$log"; then
    ok=ok
  else
    ok=failed
    status=1
  fi
  read -r seconds kib < <(tail -1 "$results.time")
  echo "$stage $ok $seconds $kib $load" >> "$rows"
  echo "-- $stage: $ok, ${seconds} s, peak $((kib / 1024)) MiB"
  [ "$ok" = ok ] || break
done
rm -f "$results.time"

python3 - "$survey" "$rows" "$results" <<'EOF'
import json, os, sys
survey, rows, results = sys.argv[1:4]
stages = []
for line in open(rows):
    name, ok, seconds, kib, load = line.split()
    stages.append({"stage": name, "status": ok, "seconds": float(seconds),
                   "peak_mib": int(kib) // 1024, "load_average": float(load)})
sim = json.load(open(os.path.join(survey, "simulation.json")))
evaluation = {}
path = os.path.join(survey, "evaluation.json")
if os.path.exists(path) and any(s["stage"] == "evaluate" and s["status"] == "ok" for s in stages):
    evaluation = json.load(open(path))
report = {}
if os.path.exists(os.path.join(survey, "report.json")):
    report = json.load(open(os.path.join(survey, "report.json"))).get("stages", {})
keyframes = sum(len(open(os.path.join(survey, "keyframes", c, "index.csv")).readlines()) - 1
                for c in sorted(os.listdir(os.path.join(survey, "keyframes")))
                if os.path.exists(os.path.join(survey, "keyframes", c, "index.csv"))) \
    if os.path.isdir(os.path.join(survey, "keyframes")) else 0
pipeline = [s for s in stages if s["stage"] not in ("evaluate", "figures")]
total = sum(s["seconds"] for s in pipeline)
out = {"survey": survey, "simulation": sim, "keyframes": keyframes, "stages": stages,
       "pipeline_seconds": total, "evaluation": evaluation}
json.dump(out, open(results + ".json", "w"), indent=2)

md = [f"# Canyon reconstruction pipeline ({os.path.basename(results)})", "",
      f"Survey `{survey}`: {sim.get('resolution')} px at {sim.get('frame_rate_hz')} fps, "
      f"sim time {sim.get('sim_time_s')} s, frames {sim.get('frames')}, {keyframes} keyframes.",
      "Timings on a shared 2-core machine (load average at each stage's start beside it).", "",
      "| stage | status | wall s | peak MiB | load |", "|---|---|---:|---:|---:|"]
for s in stages:
    md.append(f"| {s['stage']} | {s['status']} | {s['seconds']:.1f} | {s['peak_mib']} | "
              f"{s['load_average']:.1f} |")
md.append(f"| **keyframes -> textured** | | **{total:.1f}** | | |")
md.append(f"\nGoal: keyframes -> textured mesh within 15 min (900 s): "
          f"{'met' if total <= 900 and len(pipeline) == 8 and all(s['status']=='ok' for s in pipeline) else 'not met / incomplete'}.")
if evaluation:
    md += ["", "| surface | F@5cm | F@10cm | P@5cm | R@5cm | median accuracy m |",
           "|---|---:|---:|---:|---:|---:|"]
    for name, s in evaluation.get("surfaces", {}).items():
        t = {round(x["threshold_m"], 3): x for x in s["thresholds"]}
        f5, f10 = t.get(0.05, {}), t.get(0.1, {})
        md.append(f"| {name} | {f5.get('fscore', float('nan')):.3f} | "
                  f"{f10.get('fscore', float('nan')):.3f} | {f5.get('precision', float('nan')):.3f} | "
                  f"{f5.get('recall', float('nan')):.3f} | {s['accuracy_m']['median']} |")
    region = evaluation.get("region", {})
    md.append(f"\nWell-imaged region: {region.get('area_well_imaged_m2', 0):.1f} m2 "
              f"(seen by >= {region.get('min_views')} keyframes within {region.get('max_range_m')} m, "
              f"incidence <= {region.get('max_incidence_deg')} deg). Goal F@5cm >= 0.8.")
    ce = evaluation.get("camera_error", {}).get("position_m", {})
    md.append(f"Camera position error after the similarity alignment: median {ce.get('median')} m, "
              f"max {ce.get('max')} m; images matched {evaluation['images']['matched_to_truth']} "
              f"of {evaluation['images']['registered']} registered, {evaluation['images']['keyframes']} keyframes.")
    tex = evaluation.get("texture", {})
    md.append(f"Texture: {tex.get('status')}; median PSNR {tex.get('median_psnr_db')} dB, "
              f"after per-channel gain/offset {tex.get('median_psnr_gain_offset_db')} dB.")
    if "median_psnr_true_texture_db" in tex:
        md.append(f"Against the true texture: median PSNR {tex.get('median_psnr_true_texture_db')} dB, "
                  f"after per-channel gain/offset {tex.get('median_psnr_true_texture_gain_offset_db')} dB, "
                  f"CIEDE2000 {tex.get('median_delta_e_2000_true_texture')}.")
open(results + ".md", "w").write("\n".join(md) + "\n")
print("\n".join(md))
print(f"\nresults: {results}.md, {results}.json")
EOF
rm -f "$rows"
exit $status
