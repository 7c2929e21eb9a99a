#!/usr/bin/env bash
# The workspace built with clang and AddressSanitizer + UndefinedBehaviorSanitizer into
# build-asan/ and install-asan/ (the normal build/ and install/ are left alone), then its test
# suite (docs/reliability.md, "Sanitizers"). The libraries are also built with libFuzzer's
# coverage instrumentation (-fsanitize=fuzzer-no-link) and the fuzz harnesses with them
# (-DAUV_FUZZ=ON; scripts/fuzz.sh runs them). --thread: ThreadSanitizer instead, into
# build-tsan/ and install-tsan/, for the middleware and the components.
#
#   scripts/sanitize.sh              build, then every test
#   scripts/sanitize.sh --build-only
#   scripts/sanitize.sh --thread --packages-up-to auv_mapping -- --packages-select auv_interfaces auv_mapping
#   (--packages-up-to may be given more than once)
#   scripts/sanitize.sh -- <colcon test arguments>   e.g. -- --packages-select auv_mission
#
# Vendor libraries (Fast DDS, Cyclone DDS, OpenCV, Open3D, ...) are not instrumented: ASan
# still sees our accesses into their memory; UBSan's vptr check is off because it needs every
# class's type information instrumented.
set -euo pipefail
cd "$(dirname "$0")/.."
build_only=false
thread=false
build_args=()
test_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build-only) build_only=true ;;
    --thread) thread=true ;;
    --packages-up-to)
      # Repeatable: colcon builds the union of the packages and what they depend on.
      [ ${#build_args[@]} -eq 0 ] && build_args=(--packages-up-to)
      build_args+=("${2:?--packages-up-to needs a package}"); shift ;;
    --) shift; test_args=("$@"); break ;;
    *) echo "sanitize: unknown argument '$1' (--build-only, --thread, --packages-up-to PKG, -- <colcon test arguments>)" >&2; exit 2 ;;
  esac
  shift
done
for tool in clang clang++; do
  command -v "$tool" >/dev/null || { echo "sanitize: $tool not found (apt-get install clang)" >&2; exit 1; }
done
if $thread; then
  kind=tsan sanitizers=thread extra=""
else
  kind=asan sanitizers=address,undefined extra="-fno-sanitize=vptr -fsanitize=fuzzer-no-link"
fi
flags="-fsanitize=$sanitizers $extra -fno-omit-frame-pointer -g -O1"
cmake_args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++
  "-DCMAKE_C_FLAGS=$flags" "-DCMAKE_CXX_FLAGS=$flags"
  "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=$sanitizers"
  "-DCMAKE_SHARED_LINKER_FLAGS=-fsanitize=$sanitizers")
$thread || cmake_args+=(-DAUV_FUZZ=ON)
# Instrumented tests run 3-10x slower: the reconstruction's 600 s per test becomes 3000.
cmake_args+=(-DAUV_RECON_TEST_TIMEOUT=3000)
if command -v ccache >/dev/null; then
  cmake_args+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
export MAKEFLAGS="-j${AUV_BUILD_JOBS:-$(nproc)}"
colcon build --merge-install --build-base "build-$kind" --install-base "install-$kind" \
  --event-handlers console_direct+ --parallel-workers 1 "${build_args[@]}" --cmake-args "${cmake_args[@]}"
$build_only && exit 0

set +u; source "install-$kind/setup.bash"; set -u
# Reports from inside the uninstrumented vendor libraries are theirs; the suppression files
# name those libraries only (docs/reliability.md, "Sanitizers").
suppressions="$PWD/scripts/sanitizer-suppressions"
# new_delete_type_mismatch=0: Fast DDS 2.9.1 deletes a writer through the wrong type inside the
# library (asan.txt), and ASan's suppressions cannot limit this check to one library.
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:new_delete_type_mismatch=0:suppressions=$suppressions/asan.txt"
export LSAN_OPTIONS="suppressions=$suppressions/lsan.txt:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
# ignore_noninstrumented_modules: the DDS libraries are not instrumented; their own accesses
# and locks are not judged (docs/reliability.md, "Sanitizers"), ours still are (the canary).
export TSAN_OPTIONS="suppressions=$suppressions/tsan.txt:halt_on_error=1:second_deadlock_stack=1:ignore_noninstrumented_modules=1"
if $thread; then
  # clang 14's TSan cannot see glibc's clock-based locks (scripts/tsan_clock_locks.c): forward them.
  shim="$PWD/build-$kind/libtsan_clock_locks.so"
  cc -O2 -shared -fPIC -o "$shim" scripts/tsan_clock_locks.c -lpthread
  export LD_PRELOAD="$shim"
  canary="$PWD/build-$kind/tsan_canary"
  clang++ -fsanitize=thread -g -O1 -o "$canary" scripts/tsan_canary.cc
  if "$canary" 2>/dev/null; then
    echo "sanitize: TSan did not report scripts/tsan_canary.cc's race with these options" >&2
    exit 1
  fi
fi
./scripts/isolated-network.sh colcon test --merge-install --build-base "build-$kind" \
  --install-base "install-$kind" --event-handlers console_direct- console_cohesion+ \
  --return-code-on-test-failure --ctest-args --output-on-failure -j2 "${test_args[@]}"
colcon test-result --test-result-base "build-$kind" --verbose
