#!/usr/bin/env bash
# Issue #21 part 7: builds pteryla with AddressSanitizer + UndefinedBehaviorSanitizer
# (PTERYLA_SANITIZE=address,undefined, -fno-sanitize-recover=all, warnings as errors) into ./build-asan and
# runs the test suite there; extra arguments go to ctest (tools/test.sh passes `-LE "corpus|heavy"`).
# Any memory error, leak or undefined behaviour fails the test that hit it.
# -O1 -g1 with NDEBUG: about 1.2x faster to build than -O2 -g and still fast enough to test; the viewer is
# built (its scripted tests run under the sanitizers too), the Google Benchmark binaries are not.
# The GoogleTest sources themselves at -Og (PTERYLA_TEST_CXX_FLAGS, tests/CMakeLists.txt): at -O1 they were
# 55% of this build's compile time; -Og takes about 60% of that, the libraries under test keep -O1.
# PTERYLA_SHARED=ON: libpteryla.so comes out of this build, so `install_consumer` installs it instead of
# compiling the whole library a second time in a sub-build (~9 min of a core).
# PTERYLA_DEBUG_CHECKS turns the hot-loop invariant checks (PTERYLA_DCHECK, core/error.hpp) back on here.
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
[ -f build-asan/CMakeCache.txt ] && GEN=()
cmake -S . -B build-asan "${GEN[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG -DPTERYLA_DEBUG_CHECKS" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" \
  -DPTERYLA_WERROR=ON -DPTERYLA_SANITIZE=address,undefined -DPTERYLA_SHARED=ON -DPTERYLA_BUILD_VIEWER=ON \
  -DPTERYLA_BUILD_BENCHMARKS=OFF -DPTERYLA_TEST_CXX_FLAGS=-Og >/dev/null
cmake --build build-asan -j"$(nproc)"
ctest --test-dir build-asan --output-on-failure -j"$(nproc)" "$@"
