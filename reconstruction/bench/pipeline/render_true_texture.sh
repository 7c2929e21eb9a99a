#!/usr/bin/env bash
# The true texture of a simulated survey's views, for the texture figure of issue 7 (PSNR of the
# textured model re-rendered at held-out views against the simulator's renderings of the true
# texture): the survey's render folder (simulation.json's ground_truth_run, made by
# make_canyon_survey.sh) rendered again over the same span and frames in clear water
# (visibility 1000 m: no attenuation, no backscatter), without sensor noise, vignetting or
# motion blur. What remains is the world's albedo (texture x surface detail) under the
# scenario's daylight, the image a perfect colour correction would recover.
#
#   reconstruction/bench/pipeline/render_true_texture.sh [--survey DIR] [--threads N]
#
# Writes <survey>.clear/ and records it in <survey>/simulation.json as "true_texture_run", where
# `auv recon evaluate` finds it. Default survey auv_runs/survey-canyon-eval; paths relative to the
# workspace root.
set -euo pipefail
cd "$(dirname "$0")/../../.."

survey=auv_runs/survey-canyon-eval
threads=2
while [ $# -gt 0 ]; do
  case "$1" in
    --survey) survey=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    -h|--help) sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "render_true_texture: unknown option $1 (--help)" >&2; exit 2 ;;
  esac
done
[ -f "$survey/simulation.json" ] || {
  echo "render_true_texture: $survey/simulation.json not found (make_canyon_survey.sh first)" >&2
  exit 1
}
set +u; source install/setup.bash; set -u
guard=()
[ -x ../shared/tools/no-external-traffic ] && guard=(../shared/tools/no-external-traffic)

read -r truth start end < <(python3 - "$survey" <<'PY'
import json, os, sys
survey = sys.argv[1]
record = json.load(open(os.path.join(survey, "simulation.json")))
truth = os.path.normpath(os.path.join(survey, record["ground_truth_run"]))
start, end = record["sim_time_s"]
print(truth, start, end)
PY
)
clear="$survey.clear"
echo "render_true_texture: $truth -> $clear (sim time $start-$end s, clear water)"
rm -rf "$clear"
mkdir -p "$clear/ground_truth"
cp "$truth/ground_truth/trajectory.tum" "$truth/ground_truth/navigation.tum" "$clear/ground_truth/"
python3 - "$truth/scenario.yaml" "$clear/scenario.yaml" <<'PY'
import sys, yaml
source, target = sys.argv[1:3]
scenario = yaml.safe_load(open(source))
scenario["water"] = {"visibility": 1000.0}
for camera in scenario["cameras"]:
    camera.update({"noise_sigma": 0.0, "vignetting": 0.0, "exposure_time": 0.0})
with open(target, "w") as out:
    out.write("# The survey's render scenario in clear water, noise-free (render_true_texture.sh)\n")
    yaml.safe_dump(scenario, out, sort_keys=False)
PY
auv sim check "$clear/scenario.yaml" | head -2
"${guard[@]}" auv sim render "$clear" --start "$start" --end "$end" --threads "$threads" --quiet
python3 - "$survey" "$clear" <<'PY'
import json, os, sys
survey, clear = sys.argv[1:3]
path = os.path.join(survey, "simulation.json")
record = json.load(open(path))
record["true_texture_run"] = os.path.relpath(clear, survey)
with open(path + ".tmp", "w") as out:
    json.dump(record, out, indent=2)
os.replace(path + ".tmp", path)
print("render_true_texture: recorded true_texture_run in", path)
PY
