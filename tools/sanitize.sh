#!/usr/bin/env bash
# Issue #21 part 7: builds pteryla with AddressSanitizer + UndefinedBehaviorSanitizer
# (PTERYLA_SANITIZE=address,undefined, -fno-sanitize-recover) into ./build-asan and runs the whole test
# suite there. Any memory error, leak or undefined behaviour fails the test that hit it.
# The viewer and benchmarks are not built here (build time: see docs/architecture.md); the viewer's
# own tests run in the normal build.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/bootstrap.sh
export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$PWD}
# Set for the build too: gtest_discover_tests runs every test binary at build time.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:check_initialization_order=1:strict_init_order=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tools/lsan.supp:print_suppressions=0}
GEN=()
command -v ninja >/dev/null && GEN=(-G Ninja)
if [ ! -f build-asan/CMakeCache.txt ]; then
  cmake -S . -B build-asan "${GEN[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPTERYLA_WERROR=ON \
    -DPTERYLA_SANITIZE=address,undefined -DPTERYLA_BUILD_VIEWER=OFF -DPTERYLA_BUILD_BENCHMARKS=OFF >/dev/null
fi
cmake --build build-asan -j"$(nproc)"
ctest --test-dir build-asan --output-on-failure -j"$(nproc)" "$@"
