#!/usr/bin/env bash
# Builds the workspace with colcon (merged install in install/), using ccache when present.
set -euo pipefail
cd "$(dirname "$0")/.."
args=(--merge-install --event-handlers console_direct+ --parallel-workers "${AUV_BUILD_WORKERS:-1}")
cmake_args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo)
if command -v ccache >/dev/null; then
  cmake_args+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
export MAKEFLAGS="-j${AUV_BUILD_JOBS:-$(nproc)}"
colcon build "${args[@]}" --cmake-args "${cmake_args[@]}" "$@"
