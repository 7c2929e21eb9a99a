#!/usr/bin/env bash
# The main job: installs, builds, then runs a simulated inspection and its reconstruction:
#   1. the whole vehicle stack in the procedurally generated canyon (simulator, mapping,
#      planning, mission handler and controller on Cyclone DDS), inspected with `auv` from
#      Fast DDS;
#   2. the canyon inspection mission (traverse, go round the outer rock, traverse again) run
#      autonomously with `auv mission start`, faster than real time, ending with the mission
#      figure and summary (collisions, clearance, navigation error, path lengths);
#   3. the three cameras' videos of the first canyon traverse rendered from the true trajectory
#      (1352x1014 at 4 fps, reconstruction/bench/pipeline/make_canyon_survey.sh), and a survey
#      folder with the cameras' calibration;
#   4. the shore's side after recovery: `auv recon pull` (Fast DDS) fetches and verifies the
#      recordings from the vehicle's recorder (Cyclone DDS) into the survey folder;
#   5. `auv recon run`: keyframes, colour correction and undistortion, SIFT + AC-RANSAC,
#      incremental SfM, dense matching, Poisson surface, texturing -> a textured 3D model;
#   6. `auv recon evaluate` against the simulator's world (F-scores, camera error, texture PSNR)
#      and `auv recon figures` (per-camera contribution, navigation vs SfM trajectory).
# --two-visits: then a second visit of the same canyon after seeded changes (`auv sim generate
#   canyon --epoch 2`: a fallen block, a removed and a moved boulder, growth, scour, a bleached
#   patch under the first traverse): its mission, survey and reconstruction, `auv recon compare`
#   of the two surveys and `auv recon evaluate` of the change against the simulator's truth.
# Options: AUV_DEMO_WORLD (canyon), AUV_DEMO_SEED (1), AUV_DEMO_SPEED (real-time factor, 8),
#          AUV_DEMO_VIDEO_SECONDS (simulated seconds of video from 55 s, 80),
#          AUV_DEMO_RUN, AUV_DEMO_SURVEY (folders under auv_runs/),
#          AUV_DEMO_CHANGES_SEED (1: which changes the second visit finds).
set -euo pipefail
cd "$(dirname "$0")/.."
two_visits=0
for arg in "$@"; do
  case "$arg" in
    --two-visits) two_visits=1 ;;
    -h|--help) sed -n '2,30p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "run-demo: unknown option $arg (--two-visits, --help)" >&2; exit 2 ;;
  esac
done
[ $two_visits = 1 ] && [ "${AUV_DEMO_WORLD:-canyon}" != canyon ] &&
  { echo "run-demo: --two-visits is the canyon's (AUV_DEMO_WORLD=canyon)" >&2; exit 2; }
./scripts/install-deps.sh
./scripts/build.sh
set +u; source install/setup.bash; set -u
export AUV_DOMAIN_ID=42
export AUV_DEMO_WORLD=${AUV_DEMO_WORLD:-canyon} AUV_DEMO_SEED=${AUV_DEMO_SEED:-1}
export AUV_DEMO_SPEED=${AUV_DEMO_SPEED:-8}
export AUV_DEMO_VIDEO_SECONDS=${AUV_DEMO_VIDEO_SECONDS:-80}
export AUV_DEMO_RUN=${AUV_DEMO_RUN:-auv_runs/demo-$AUV_DEMO_WORLD}
export AUV_DEMO_SURVEY=${AUV_DEMO_SURVEY:-auv_runs/survey-$AUV_DEMO_WORLD}
guard=()
[ -x ../shared/tools/no-external-traffic ] && guard=(../shared/tools/no-external-traffic)

"${guard[@]}" bash -c '
set -euo pipefail
step() { printf "\n\033[1m== %s\033[0m\n" "$*"; }
rm -rf "$AUV_DEMO_RUN"
step "auv launch bringup/launch/vehicle.yaml world:=$AUV_DEMO_WORLD real_time_factor:=$AUV_DEMO_SPEED"
auv launch bringup/launch/vehicle.yaml world:=$AUV_DEMO_WORLD seed:=$AUV_DEMO_SEED \
  real_time_factor:=$AUV_DEMO_SPEED domain:=42 run_dir:="$AUV_DEMO_RUN" > /tmp/auv-demo-vehicle.log 2>&1 &
launch_pid=$!
trap "kill -INT $launch_pid 2>/dev/null; wait $launch_pid || true" EXIT
# The first launch generates the world from its seed into the world cache (~10 s).
for i in $(seq 1 120); do grep -q "run folder" /tmp/auv-demo-vehicle.log && break; sleep 0.5; done
step "auv sim check $AUV_DEMO_RUN/scenario.yaml   (the world the simulator loaded)"
auv sim check "$AUV_DEMO_RUN/scenario.yaml"
step "AUV_DDS=fastdds auv topic list -t   (the vehicle runs Cyclone DDS)"
AUV_DDS=fastdds auv topic list -t
for topic in nav/odometry sonar/beam map/update; do
  step "auv topic hz $topic --duration 2"
  AUV_DDS=fastdds auv topic hz $topic --duration 2 | tail -1
done
step "auv mission start $AUV_DEMO_RUN/mission.yaml --wait   (the world'"'"'s inspection mission)"
cat "$AUV_DEMO_RUN/mission.yaml"
status=0
AUV_DDS=fastdds auv mission start "$AUV_DEMO_RUN/mission.yaml" --wait --report "$AUV_DEMO_RUN" || status=$?
step "auv mission status"
auv mission status || true
kill -INT $launch_pid; wait $launch_pid || true; trap - EXIT
grep -E "COLLISION" /tmp/auv-demo-vehicle.log | tail -3 || true
[ $status = 0 ] || { echo "demo: the mission did not succeed: no survey (run folder $AUV_DEMO_RUN)" >&2; exit $status; }
step "survey cameras: make_canyon_survey.sh --run $AUV_DEMO_RUN --seconds $AUV_DEMO_VIDEO_SECONDS   (rendered from the true trajectory)"
reconstruction/bench/pipeline/make_canyon_survey.sh --run "$AUV_DEMO_RUN" --survey "$AUV_DEMO_SURVEY" \
  --seconds "$AUV_DEMO_VIDEO_SECONDS" --no-recordings
step "auv recon pull --vehicle auv --into $AUV_DEMO_SURVEY   (shore on Fast DDS; the recorder on Cyclone DDS)"
auv run recorder -p root:="$AUV_DEMO_SURVEY.truth/vehicle/recordings" -p vehicle_name:=auv \
  > /tmp/auv-demo-recorder.log 2>&1 &
recorder_pid=$!
AUV_DDS=fastdds auv recon pull --vehicle auv --into "$AUV_DEMO_SURVEY" --timeout 30 || status=$?
kill -INT $recorder_pid; wait $recorder_pid || true
[ $status = 0 ] || exit $status
step "auv recon run $AUV_DEMO_SURVEY   (keyframes -> textured model)"
auv recon run "$AUV_DEMO_SURVEY"
step "auv recon evaluate $AUV_DEMO_SURVEY   (against the simulated world)"
auv recon evaluate "$AUV_DEMO_SURVEY" || status=$?
step "auv recon figures $AUV_DEMO_SURVEY"
auv recon figures "$AUV_DEMO_SURVEY" || status=$?
step "results"
echo "  mission figure  $AUV_DEMO_RUN/mission/report.png (and .svg); summary $AUV_DEMO_RUN/mission/summary.json"
for f in sparse/points.ply dense/fused.ply mesh/mesh.ply textured/model.obj figures/cameras.png \
         figures/trajectory.png evaluation.json report.json; do
  echo "  $(printf "%-18s" "$f") $AUV_DEMO_SURVEY/$f"
done
exit $status
'
echo
echo "demo: done (traffic stayed on loopback); run folder: $AUV_DEMO_RUN, survey: $AUV_DEMO_SURVEY"
[ $two_visits = 1 ] || exit 0

export AUV_DEMO_CHANGES_SEED=${AUV_DEMO_CHANGES_SEED:-1}
export AUV_DEMO_SITE2=auv_runs/canyon-epoch2-site AUV_DEMO_RUN2=$AUV_DEMO_RUN-2
export AUV_DEMO_SURVEY2=$AUV_DEMO_SURVEY-2
"${guard[@]}" bash -c '
set -euo pipefail
step() { printf "\n\033[1m== %s\033[0m\n" "$*"; }
step "auv sim generate canyon --seed $AUV_DEMO_SEED --epoch 2 --changes-seed $AUV_DEMO_CHANGES_SEED   (the site, changed)"
auv sim generate canyon --seed "$AUV_DEMO_SEED" --epoch 2 --changes-seed "$AUV_DEMO_CHANGES_SEED" \
  --out "$AUV_DEMO_SITE2"
sed -n "/^changes:/,\$p" "$AUV_DEMO_SITE2/canyon_epoch2.yaml"
step "second visit: mission from the first visit'"'"'s map, cameras and survey (make_canyon_survey.sh --world $AUV_DEMO_SITE2/canyon_epoch2.yaml --initial-map $AUV_DEMO_RUN/mission/map.bt)"
rm -rf "$AUV_DEMO_RUN2"
reconstruction/bench/pipeline/make_canyon_survey.sh --world "$AUV_DEMO_SITE2/canyon_epoch2.yaml" \
  --seed 2 --run "$AUV_DEMO_RUN2" --survey "$AUV_DEMO_SURVEY2" --seconds "$AUV_DEMO_VIDEO_SECONDS" \
  --initial-map "$AUV_DEMO_RUN/mission/map.bt"
cat "$AUV_DEMO_RUN2/maps/prior_alignment.json" 2>/dev/null || true
step "auv recon run $AUV_DEMO_SURVEY2"
auv recon run "$AUV_DEMO_SURVEY2"
step "auv recon compare $AUV_DEMO_SURVEY $AUV_DEMO_SURVEY2   (what changed)"
status=0
auv recon compare "$AUV_DEMO_SURVEY" "$AUV_DEMO_SURVEY2" || status=$?
step "auv recon evaluate $AUV_DEMO_SURVEY2   (the model and the change against the truth)"
auv recon evaluate "$AUV_DEMO_SURVEY2" || status=$?
step "results"
for f in change/changes.ply change/change_map.png change/mesh_change.ply change/report.json \
         evaluation.json; do
  echo "  $(printf "%-22s" "$f") $AUV_DEMO_SURVEY2/$f"
done
exit $status
'
echo
echo "demo: second visit done; survey $AUV_DEMO_SURVEY2, changes in $AUV_DEMO_SURVEY2/change/"
