#!/usr/bin/env bash
# The simulated canyon survey every reconstruction figure of issues 6 and 7 is measured on.
#
#   1. the canyon inspection mission (auv launch bringup/launch/vehicle.yaml, auto_mission) on
#      DDS domain 46 (--domain), or a finished run given with --run (reused when it succeeded);
#   2. a render folder beside it: the run's scenario with the survey's camera settings
#      (1352 x 1014, 4 fps, water visibility 12 m), its true and navigation trajectories, and
#      the three cameras rendered over the chosen span with `auv sim render` (the ground truth
#      the evaluation reads: ground_truth/cameras.txt, images_<camera>.txt);
#   3. the survey folder: recordings/<camera>/ (videos + frame-time sidecars, as `auv recon
#      pull` leaves them), calibration/<camera>.yaml (the simulator's true intrinsics in
#      OpenCV FileStorage; --calibrate renders chessboard videos and runs `auv recon
#      calibrate` instead), and simulation.json recording where the ground truth is
#      (`auv recon evaluate <survey>` finds it there).
#      navigation.tum is the vehicle's navigation estimate (match places keyframes with it).
#
# Why these settings (reconstruction/bench/pipeline/README.md): at the scenario's 4.5 m the
# simulator's water (Koschmieder: 2 % contrast at the visibility) leaves the canyon walls 2-4 m
# away as faint haze at the image edges; at 12 m both walls and the floor are textured.
# 4 fps moves the image ~25 px between frames at 2 m (0.23 m/s): easy for Lucas-Kanade.
# Default span: 80 s of the first canyon traverse (55-135 s after the mission started, the first
# row of <run>/mission/events.csv: the vehicle enters the canyon ~55 s after it sets off), 960 frames, ~10 CPU-minutes of rendering. --full: 400 s (55-455 s: the
# traverse and most of the way round the outer rock), 4800 frames, for ~300 keyframes. Usage:
#   reconstruction/bench/pipeline/make_canyon_survey.sh [--survey DIR] [--run DIR] [--full]
#       [--start S] [--seconds S] [--fps F] [--width W] [--height H] [--visibility M]
#       [--threads N] [--seed N] [--world NAME|SCENARIO.yaml] [--initial-map MAP.bt]
#       [--calibrate] [--no-recordings] [--domain N] [--reuse-render]
# --world: the world of the mission (default canyon), e.g. a later visit of the canyon with its
# changes (`auv sim generate canyon --epoch 2`: <dir>/canyon_epoch2.yaml); --seed is then the
# sensors' noise only. --initial-map MAP.bt: the mission starts from an earlier visit's map
# (<run>/mission/map.bt), aligned to this visit's sonar returns before it is trusted.
# --reuse-render keeps a render folder that holds every camera's video (e.g. after a survey
# step failed): only the survey folder is made again.
# --no-recordings leaves recordings/ to `auv recon pull` from a recorder serving
# <survey>.truth/vehicle/recordings (what scripts/run-demo.sh does).
# Paths are relative to the workspace root (default survey auv_runs/survey-canyon-eval, mission
# run auv_runs/canyon-survey-mission, render folder <survey>.truth).
set -euo pipefail
cd "$(dirname "$0")/../../.."
ROOT=$PWD

survey=auv_runs/survey-canyon-eval
run=auv_runs/canyon-survey-mission
start=55
seconds=80
fps=4
width=1352
height=1014
visibility=12
threads=2
seed=1
world=canyon
initial_map=
calibrate=0
recordings=1
domain=46
reuse_render=0
while [ $# -gt 0 ]; do
  case "$1" in
    --survey) survey=$2; shift 2 ;;
    --run) run=$2; shift 2 ;;
    --full) start=55; seconds=400; shift ;;
    --start) start=$2; shift 2 ;;
    --seconds) seconds=$2; shift 2 ;;
    --fps) fps=$2; shift 2 ;;
    --width) width=$2; shift 2 ;;
    --height) height=$2; shift 2 ;;
    --visibility) visibility=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --world) world=$2; shift 2 ;;
    --initial-map) initial_map=$2; shift 2 ;;
    --calibrate) calibrate=1; shift ;;
    --no-recordings) recordings=0; shift ;;
    --domain) domain=$2; shift 2 ;;
    --reuse-render) reuse_render=1; shift ;;
    -h|--help) sed -n '2,30p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "make_canyon_survey: unknown option $1 (--help)" >&2; exit 2 ;;
  esac
done
truth="$survey.truth"

set +u; source install/setup.bash; set -u
guard=()
[ -x ../shared/tools/no-external-traffic ] && guard=(../shared/tools/no-external-traffic)
step() { printf '\n\033[1m== %s\033[0m\n' "$*"; }
t0=$(date +%s)

# 1. The mission (domain 46 by default: test/README.md's table; never two runs on one domain).
if python3 - "$run" <<'EOF'
import json, sys
try:
    ok = json.load(open(sys.argv[1] + "/mission/summary.json"))["state"] == "SUCCEEDED"
except Exception:
    ok = False
sys.exit(0 if ok else 1)
EOF
then
  step "reusing the finished mission $run"
else
  step "mission in $world (seed $seed) on domain $domain -> $run"
  rm -rf "$run"
  "${guard[@]}" auv launch bringup/launch/vehicle.yaml world:="$world" seed:="$seed" \
    real_time_factor:=8 domain:="$domain" run_dir:="$run" auto_mission:=true recorder:=false \
    ${initial_map:+initial_map:="$initial_map"} \
    > "$run.log" 2>&1 || { echo "make_canyon_survey: the mission failed, see $run.log" >&2; exit 1; }
  python3 -c "import json,sys; s=json.load(open('$run/mission/summary.json')); print('mission:', s['state'], s['message'])"
fi
t1=$(date +%s)

# 2. The render folder: the run's scenario with the survey's cameras, its trajectories.
# --start counts from the mission's start: a mission started by hand (the main job inspects the
# vehicle first) sets off later in simulated time than an auto_mission run.
mission_start=$(python3 - "$run/mission/events.csv" <<'EOF'
import csv, sys
try:
    print(float(next(csv.DictReader(open(sys.argv[1])))["t"]))
except Exception:
    print(0.0)
EOF
)
start=$(python3 -c "print(round($mission_start + $start, 2))")
end=$(python3 -c "print(round($start + $seconds, 2))")
if [ "$reuse_render" = 1 ] && ls "$truth"/vehicle/recordings/*/*.mp4 > /dev/null 2>&1; then
  step "reusing the render folder $truth"
else
  step "render folder $truth: ${width}x${height} at $fps fps, sim time $start-$end s (mission start $mission_start s)"
  rm -rf "$truth"
  mkdir -p "$truth/ground_truth"
  cp "$run/ground_truth/trajectory.tum" "$run/ground_truth/navigation.tum" "$truth/ground_truth/"
  [ -f "$run/mission/summary.json" ] && mkdir -p "$truth/mission" && cp "$run/mission/summary.json" "$truth/mission/"
  python3 - "$run/scenario.yaml" "$truth/scenario.yaml" "$width" "$height" "$fps" "$visibility" <<'EOF'
import sys, yaml
source, target, width, height, fps, visibility = sys.argv[1:7]
scenario = yaml.safe_load(open(source))
cameras = scenario.get("cameras") or [{"id": i} for i in ("left", "right", "forward")]
for camera in cameras:
    camera.update({"width": int(width), "height": int(height), "frame_rate": float(fps)})
scenario["cameras"] = cameras
if visibility:
    scenario["water"] = {"visibility": float(visibility)}
with open(target, "w") as out:
    out.write("# The mission's scenario with the survey's camera settings (make_canyon_survey.sh)\n")
    yaml.safe_dump(scenario, out, sort_keys=False)
EOF
  auv sim check "$truth/scenario.yaml" | head -3
  "${guard[@]}" auv sim render "$truth" --start "$start" --end "$end" --threads "$threads" \
    --progress-every 30
fi
t2=$(date +%s)

# 3. The survey folder.
step "survey $survey"
rm -rf "$survey"
mkdir -p "$survey/recordings" "$survey/calibration"
# The vehicle's navigation estimate (drifting dead reckoning, not the truth), as the vehicle
# logs it: `auv recon match` places keyframes with it (look-alike surfaces far apart are not
# matched).
cp "$truth/ground_truth/navigation.tum" "$survey/navigation.tum"
if [ "$recordings" = 1 ]; then
  for dir in "$truth"/vehicle/recordings/*/; do
    camera=$(basename "$dir")
    mkdir -p "$survey/recordings/$camera"
    cp "$dir"/*.mp4 "$dir"/*.frames.csv "$survey/recordings/$camera/"
  done
fi
if [ "$calibrate" = 1 ]; then
  auv sim calibration "$truth/scenario.yaml" --out "$survey.chessboard" --frames 40 \
    --threads "$threads" --quiet
  for video in "$survey.chessboard"/*.mp4; do
    camera=$(basename "$video" .mp4)
    auv recon calibrate "$survey" --camera "$camera" --input "$video"
  done
else
  # The true intrinsics of ground_truth/cameras.txt (COLMAP: principal point + 0.5 px).
  python3 - "$truth/ground_truth" "$survey/calibration" <<'EOF'
import glob, os, sys
truth, out = sys.argv[1:3]
lens = {}
for line in open(os.path.join(truth, "cameras.txt")):
    if line.startswith("#") or not line.strip():
        continue
    f = line.split()
    lens[f[0]] = (f[1], int(f[2]), int(f[3]), [float(v) for v in f[4:]])
for images in sorted(glob.glob(os.path.join(truth, "images_*.txt"))):
    camera = os.path.basename(images)[len("images_"):-4]
    camera_id = next(l.split()[8] for l in open(images) if l.strip() and not l.startswith("#"))
    model, w, h, p = lens[camera_id]
    fx, fy, cx, cy = p[0], p[1], p[2] - 0.5, p[3] - 0.5
    dist = p[4:] if model in ("OPENCV", "FULL_OPENCV") else []
    with open(os.path.join(out, camera + ".yaml"), "w") as y:
        y.write("%YAML:1.0\n---\n")
        y.write(f"image_width: {w}\nimage_height: {h}\n")
        y.write("camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n")
        y.write(f"   data: [ {fx!r}, 0., {cx!r}, 0., {fy!r}, {cy!r}, 0., 0., 1. ]\n")
        y.write(f"distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: {len(dist)}\n   dt: d\n")
        y.write("   data: [ " + ", ".join(repr(v) for v in dist) + " ]\n")
        y.write("rms_reprojection_error_px: 0.\n")
        y.write('source: "simulator ground truth (make_canyon_survey.sh)"\n')
    print(f"calibration/{camera}.yaml: {model} {w}x{h} fx {fx:.2f} cx {cx:.2f} cy {cy:.2f} k {dist}")
EOF
fi
python3 - "$survey" "$truth" "$run" "$start" "$end" "$fps" "$width" "$height" "$visibility" \
  "$((t1 - t0))" "$((t2 - t1))" <<'EOF'
import glob, json, os, sys
survey, truth, run, start, end, fps, width, height, visibility, mission_s, render_s = sys.argv[1:12]
frames = {}
for sidecar in sorted(glob.glob(os.path.join(truth, "vehicle", "recordings", "*", "*.frames.csv"))):
    frames[os.path.basename(os.path.dirname(sidecar))] = sum(1 for _ in open(sidecar)) - 1
record = {
    "ground_truth_run": os.path.relpath(truth, survey),
    "mission_run": os.path.relpath(run, survey),
    "world": "canyon",
    "sim_time_s": [float(start), float(end)],
    "frame_rate_hz": float(fps),
    "resolution": [int(width), int(height)],
    "visibility_m": float(visibility) if visibility else "scenario",
    "frames": frames,
    "mission_seconds": int(mission_s),
    "render_seconds": int(render_s),
}
with open(os.path.join(survey, "simulation.json"), "w") as out:
    json.dump(record, out, indent=2)
print("simulation.json:", json.dumps(record))
EOF
step "done in $(( $(date +%s) - t0 )) s: survey $survey (ground truth $truth)"
echo "next: auv recon run $survey   then   auv recon evaluate $survey"
