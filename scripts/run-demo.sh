#!/usr/bin/env bash
# The main job: installs, builds, then runs the richest end-to-end run we have so far:
#   1. the simulated vehicle in the procedurally generated canyon (simulator on Cyclone DDS,
#      low-level controller), inspected with `auv` from Fast DDS;
#   2. a waypoint sent by hand through the canyon, the controller's status and the ground-truth
#      collision events;
#   3. the cameras' videos rendered from the run's true trajectory (`auv sim render`).
# Later issues add the autonomous mission (mapping, planning) and the 3D reconstruction.
# Options: AUV_DEMO_WORLD (canyon), AUV_DEMO_SECONDS (simulated seconds, 60),
#          AUV_DEMO_SCALE (video resolution scale, 0.5 of 960x720).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
./scripts/build.sh
set +u; source install/setup.bash; set -u
export AUV_DOMAIN_ID=42
export AUV_DEMO_WORLD=${AUV_DEMO_WORLD:-canyon} AUV_DEMO_SECONDS=${AUV_DEMO_SECONDS:-60}
export AUV_DEMO_SCALE=${AUV_DEMO_SCALE:-0.5}
export AUV_DEMO_RUN=${AUV_DEMO_RUN:-auv_runs/demo-$AUV_DEMO_WORLD}
guard=()
[ -x ../shared/tools/no-external-traffic ] && guard=(../shared/tools/no-external-traffic)

"${guard[@]}" bash -c '
set -euo pipefail
step() { printf "\n\033[1m== %s\033[0m\n" "$*"; }
rm -rf "$AUV_DEMO_RUN"
step "auv launch bringup/launch/sim.yaml world:=$AUV_DEMO_WORLD real_time_factor:=4   (simulator + controller)"
auv launch bringup/launch/sim.yaml world:=$AUV_DEMO_WORLD real_time_factor:=4 domain:=42 \
  run_dir:="$AUV_DEMO_RUN" > /tmp/auv-demo-sim.log 2>&1 &
launch_pid=$!
trap "kill -INT $launch_pid 2>/dev/null; wait $launch_pid || true" EXIT
# The first launch generates the world from its seed into the world cache (~10 s).
for i in $(seq 1 120); do grep -q "run folder" /tmp/auv-demo-sim.log && break; sleep 0.5; done
step "auv sim check $AUV_DEMO_RUN/scenario.yaml   (the world the simulator loaded)"
auv sim check "$AUV_DEMO_RUN/scenario.yaml"
step "AUV_DDS=fastdds auv topic list -t"
AUV_DDS=fastdds auv topic list -t
for topic in clock nav/odometry sonar/beam; do
  step "auv topic hz $topic --duration 2"
  AUV_DDS=fastdds auv topic hz $topic --duration 2 | tail -1
done
step "auv topic echo sonar/beam --once --field ranges"
auv topic echo sonar/beam --once --field ranges
goal=$(python3 -c "import yaml,sys; s=yaml.safe_load(open(\"$AUV_DEMO_RUN/scenario.yaml\")); g=s[\"queries\"][0][\"goal\"]; print(\"{x: %s, y: %s, z: %s}\" % tuple(g))")
step "auv topic pub control/waypoint ControllerCommand (to the first query goal $goal, straight: no planner yet)"
AUV_DDS=fastdds auv topic pub control/waypoint ControllerCommand \
  "{command_id: 1, mode: CONTROL_MODE_WAYPOINT, position: $goal, surge_speed: 0.8, tolerance: 2.0}" --times 1
sleep 2
step "auv topic echo control/status --once"
auv topic echo control/status --once --field state
auv topic echo control/status --once --field distance_to_target
step "waiting for $AUV_DEMO_SECONDS simulated seconds (ground-truth collisions are logged as they happen)"
end=$(( $(date +%s) + AUV_DEMO_SECONDS / 4 + 2 ))
while [ "$(date +%s)" -lt "$end" ]; do sleep 1; done
auv topic echo sim/ground_truth --once --field pose.pose.position
kill -INT $launch_pid; wait $launch_pid || true; trap - EXIT
grep -E "COLLISION|reached|exited" /tmp/auv-demo-sim.log | tail -5 || true
echo "collision events: $(($(wc -l < "$AUV_DEMO_RUN/ground_truth/collisions.csv") - 1))"
step "auv sim render $AUV_DEMO_RUN --scale $AUV_DEMO_SCALE   (cameras from the true trajectory)"
auv sim render "$AUV_DEMO_RUN" --scale "$AUV_DEMO_SCALE"
find "$AUV_DEMO_RUN" -type f | sort | sed "s/^/  /"
'
echo
echo "demo: done (traffic stayed on loopback); run folder: $AUV_DEMO_RUN"
