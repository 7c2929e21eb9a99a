#!/usr/bin/env bash
# Installs, builds, and runs every test (colcon test + test-result); exits non-zero on failure.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)
./scripts/install-deps.sh
./scripts/build.sh
set +u; source install/setup.bash; set -u
guard=()
[ -x ../shared/tools/no-external-traffic ] && guard=(../shared/tools/no-external-traffic)
status=0
# In a network namespace of its own, DDS ports kept out of the ephemeral range (see the script).
"${guard[@]}" ./scripts/isolated-network.sh colcon test --merge-install --event-handlers console_direct- console_cohesion+ \
  --return-code-on-test-failure --ctest-args --output-on-failure -j2 || status=$?
if [ $status -eq 97 ]; then
  # The guard counts every process of the host; the tests themselves only use loopback.
  echo "run-tests: WARNING: a non-loopback interface sent packets while the tests ran" \
       "(other processes count too; see ../shared/tools/no-external-traffic)" >&2
  status=0
fi
colcon test-result --verbose || status=1
echo "run-tests: finished in $(( $(date +%s) - start )) s with status $status"
exit $status
