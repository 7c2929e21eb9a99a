#!/usr/bin/env bash
# The workspace built with clang and AddressSanitizer + UndefinedBehaviorSanitizer into
# build-asan/ and install-asan/ (the normal build/ and install/ are left alone), then its test
# suite (docs/reliability.md, "Sanitizers"). The libraries are also built with libFuzzer's
# coverage instrumentation (-fsanitize=fuzzer-no-link), so the fuzz harnesses link against
# them.
#
#   scripts/sanitize.sh              build, then every test
#   scripts/sanitize.sh --build-only
#   scripts/sanitize.sh -- <colcon test arguments>   e.g. -- --packages-select auv_mission
#
# Vendor libraries (Fast DDS, Cyclone DDS, OpenCV, Open3D, ...) are not instrumented: ASan
# still sees our accesses into their memory; UBSan's vptr check is off because it needs every
# class's type information instrumented.
set -euo pipefail
cd "$(dirname "$0")/.."
build_only=false
test_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build-only) build_only=true ;;
    --) shift; test_args=("$@"); break ;;
    *) echo "sanitize: unknown argument '$1' (--build-only, -- <colcon test arguments>)" >&2; exit 2 ;;
  esac
  shift
done
for tool in clang clang++; do
  command -v "$tool" >/dev/null || { echo "sanitize: $tool not found (apt-get install clang)" >&2; exit 1; }
done
flags="-fsanitize=address,undefined -fno-sanitize=vptr -fsanitize=fuzzer-no-link -fno-omit-frame-pointer -g -O1"
cmake_args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++
  "-DCMAKE_C_FLAGS=$flags" "-DCMAKE_CXX_FLAGS=$flags"
  "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined"
  "-DCMAKE_SHARED_LINKER_FLAGS=-fsanitize=address,undefined" -DAUV_FUZZ=ON)
if command -v ccache >/dev/null; then
  cmake_args+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
export MAKEFLAGS="-j${AUV_BUILD_JOBS:-$(nproc)}"
colcon build --merge-install --build-base build-asan --install-base install-asan \
  --event-handlers console_direct+ --parallel-workers 1 --cmake-args "${cmake_args[@]}"
$build_only && exit 0

set +u; source install-asan/setup.bash; set -u
# Leaks of the uninstrumented vendor libraries at exit are theirs; the suppressions name them.
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1"
export LSAN_OPTIONS="suppressions=$PWD/scripts/sanitizer-suppressions/lsan.txt:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
./scripts/isolated-network.sh colcon test --merge-install --build-base build-asan \
  --install-base install-asan --event-handlers console_direct- console_cohesion+ \
  --return-code-on-test-failure --ctest-args --output-on-failure -j2 "${test_args[@]}"
colcon test-result --test-result-base build-asan --verbose
