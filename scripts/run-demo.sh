#!/usr/bin/env bash
# The main job: installs, builds, then runs the richest end-to-end run we have so far —
# components on Fast DDS and Cyclone DDS talking to each other, inspected with `auv`.
# Later issues grow this into a simulated inspection mission and its reconstruction.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
./scripts/build.sh
set +u; source install/setup.bash; set -u
export AUV_DOMAIN_ID=42
guard=()
[ -x ../shared/tools/no-external-traffic ] && guard=(../shared/tools/no-external-traffic)

"${guard[@]}" bash -c '
set -u
step() { printf "\n\033[1m== %s\033[0m\n" "$*"; }
step "auv launch bringup/launch/demo.yaml (talker on Fast DDS, listener on Cyclone DDS, both composed)"
auv launch bringup/launch/demo.yaml > /tmp/auv-demo-launch.log 2>&1 &
launch_pid=$!
trap "kill -INT $launch_pid 2>/dev/null; wait $launch_pid" EXIT
sleep 3
step "AUV_DDS=cyclonedds auv node list -v"
AUV_DDS=cyclonedds auv node list -v
step "AUV_DDS=fastdds auv topic list -t"
AUV_DDS=fastdds auv topic list -t
step "auv topic info /chatter -v   (publishers of both vendors)"
auv topic info /chatter -v | grep -E "^(Type|Publisher|Subscription|Node name|Vendor|Endpoint type|  Reliability|  Durability)"
step "AUV_DDS=fastdds auv topic echo /chatter --once   (Fast DDS reads both vendors)"
AUV_DDS=fastdds auv topic echo /chatter --once
step "AUV_DDS=fastdds auv topic echo /demo/status --once   (late joiner, transient local, from Cyclone)"
AUV_DDS=fastdds auv topic echo /demo/status --once --field message
step "auv topic echo /nav/odometry --once --field pose.pose.position"
auv topic echo /nav/odometry --once --field pose.pose.position
step "auv topic hz /chatter --duration 3"
auv topic hz /chatter --duration 3 | tail -2
step "AUV_DDS=fastdds auv topic pub /chatter String \"{data: hello from the CLI}\" --times 3 --rate 5"
AUV_DDS=fastdds auv topic pub /chatter String "{data: hello from the CLI}" --times 3 --rate 5
sleep 1
step "launch log (last lines: listeners on Cyclone heard Fast DDS and CLI messages)"
kill -INT $launch_pid; wait $launch_pid; trap - EXIT
grep -E "heard|talking|exited|stopped" /tmp/auv-demo-launch.log | tail -12
'
echo
echo "demo: done (traffic stayed on loopback)"
