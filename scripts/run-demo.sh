#!/usr/bin/env bash
# The main job: installs, builds, then runs the richest end-to-end run we have so far:
#   1. the whole vehicle stack in the procedurally generated canyon (simulator, mapping,
#      planning, mission handler and controller on Cyclone DDS), inspected with `auv` from
#      Fast DDS;
#   2. the canyon inspection mission (traverse, go round the outer rock, traverse again) run
#      autonomously with `auv mission start`, faster than real time, ending with the mission
#      figure and summary (collisions, clearance, navigation error, path lengths);
#   3. the cameras' videos of part of the mission rendered from the true trajectory;
#   4. the shore's side after recovery: `auv recon pull` (Fast DDS) fetches and verifies the
#      recordings from the vehicle's recorder (Cyclone DDS) into a survey folder.
# The 3D reconstruction comes with a later issue.
# Options: AUV_DEMO_WORLD (canyon), AUV_DEMO_SEED (1), AUV_DEMO_SPEED (real-time factor, 8),
#          AUV_DEMO_SCALE (video resolution scale, 0.5 of 960x720),
#          AUV_DEMO_VIDEO_SECONDS (simulated seconds of video rendered, 60; 0 = the whole run).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
./scripts/build.sh
set +u; source install/setup.bash; set -u
export AUV_DOMAIN_ID=42
export AUV_DEMO_WORLD=${AUV_DEMO_WORLD:-canyon} AUV_DEMO_SEED=${AUV_DEMO_SEED:-1}
export AUV_DEMO_SPEED=${AUV_DEMO_SPEED:-8} AUV_DEMO_SCALE=${AUV_DEMO_SCALE:-0.5}
export AUV_DEMO_VIDEO_SECONDS=${AUV_DEMO_VIDEO_SECONDS:-60}
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
end=""
[ "$AUV_DEMO_VIDEO_SECONDS" != 0 ] && end="--end $AUV_DEMO_VIDEO_SECONDS"
step "auv sim render $AUV_DEMO_RUN --scale $AUV_DEMO_SCALE $end   (cameras from the true trajectory)"
auv sim render "$AUV_DEMO_RUN" --scale "$AUV_DEMO_SCALE" $end --quiet
find "$AUV_DEMO_RUN" -type f -not -name "tree_*" | sort | sed "s/^/  /"
step "auv recon pull --vehicle auv --into $AUV_DEMO_SURVEY   (shore on Fast DDS; the recorder on Cyclone DDS)"
rm -rf "$AUV_DEMO_SURVEY"
auv run recorder -p root:="$AUV_DEMO_RUN/vehicle/recordings" -p vehicle_name:=auv \
  > /tmp/auv-demo-recorder.log 2>&1 &
recorder_pid=$!
AUV_DDS=fastdds auv recon pull --vehicle auv --into "$AUV_DEMO_SURVEY" --timeout 30 || status=$?
kill -INT $recorder_pid; wait $recorder_pid || true
find "$AUV_DEMO_SURVEY" -type f | sort | sed "s/^/  /"
step "mission figure: $AUV_DEMO_RUN/mission/report.png (and .svg); summary: $AUV_DEMO_RUN/mission/summary.json"
exit $status
'
echo
echo "demo: done (traffic stayed on loopback); run folder: $AUV_DEMO_RUN"
