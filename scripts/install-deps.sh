#!/usr/bin/env bash
# Installs every Debian 12 package the workspace needs. Idempotent; uses only apt.
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

PACKAGES=(
  # build tools
  build-essential cmake ccache python3 python3-yaml git iproute2
  colcon python3-colcon-cmake python3-colcon-recursive-crawl python3-colcon-parallel-executor
  python3-colcon-output python3-colcon-package-selection python3-colcon-bash
  python3-colcon-defaults python3-colcon-metadata python3-colcon-package-information
  python3-colcon-test-result python3-colcon-library-path
  # DDS vendors (both always built) and their generators/tools
  libfastrtps-dev libfastcdr-dev fastddsgen fastdds-tools cyclonedds-dev cyclonedds-tools
  # common libraries and tests
  libyaml-cpp-dev libgtest-dev libgmock-dev libbenchmark-dev
  # simulator: geometry, ray casting (Embree), meshes (Open3D), images and H.264 video
  libeigen3-dev libembree-dev libopen3d-dev libfmt-dev libopencv-dev ffmpeg
  # vehicle autonomy: maps, distance fields, planning
  liboctomap-dev libdynamicedt3d-dev octomap-tools libompl-dev
  # recordings pull: SHA-256 (OpenSSL EVP), manifest JSON; rsync is the pull benchmark's anchor
  libssl-dev nlohmann-json3-dev rsync
  # reconstruction: bundle adjustment (Ceres); COLMAP is the SfM benchmark's anchor, opencv-doc
  # ships real chessboard photos for the calibration tests
  libceres-dev colmap opencv-doc
  # the COLMAP benchmark reads COLMAP's database (pairs matched and verified)
  sqlite3
  # reconstruction: the 5-point relative-pose solver of AC-RANSAC's essential matrix (OpenGV)
  libopengv-dev
  # reconstruction import: EXIF of photos from anywhere (libexiv2); exiv2 writes test EXIF
  libexiv2-dev exiv2
  # reconstruction texturing: max-flow (Boost.Graph, header-only), atlas packing (stb_rect_pack)
  libboost-dev libstb-dev
  # reconstruction pipeline benchmark: wall time and peak memory per stage (GNU time)
  time
  # change detection: CloudCompare (command-line mode) reads the change clouds in the tests
  cloudcompare
  # bags (MCAP chunk compression) and the Foxglove bridge (WebSocket server, header-only)
  libzstd-dev liblz4-dev zlib1g-dev libwebsocketpp-dev libasio-dev
  # auv view: levels of detail that keep texture coordinates (meshoptimizer); headless Chromium
  # for the page's tests and benchmark (puppeteer-core drives it, js/README.md)
  libmeshoptimizer-dev chromium
  # two-host tests: the link impairer (test/two_host/link_impair.cc) takes packets from an
  # iptables NFQUEUE rule (libnetfilter_queue) to drop, delay and reorder them
  iptables libnetfilter-queue-dev
  # the reconstruction on a cluster: Slurm and munge (scripts/slurm-cluster.sh runs a private
  # cluster for the tests)
  slurmctld slurmd slurm-client munge
)

echo "install-deps: apt-get update"
$SUDO apt-get update -qq
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages already installed"
else
  echo "install-deps: installing ${missing[*]}"
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends "${missing[@]}"
fi

# Reference clients the tests check us against (js/README.md): Node.js and npm from Debian
# unless the machine already has them, then the pinned modules of js/package-lock.json.
if ! command -v npm >/dev/null 2>&1; then
  echo "install-deps: installing nodejs npm"
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends nodejs npm
fi
js_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/js"
if [ ! -d "$js_dir/node_modules" ] || [ "$js_dir/package-lock.json" -nt "$js_dir/node_modules" ]; then
  echo "install-deps: npm ci in js/"
  (cd "$js_dir" && npm ci --no-audit --no-fund)
  touch "$js_dir/node_modules"
fi
