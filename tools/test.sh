#!/usr/bin/env bash
# README command 2 (and .ci/run): build with warnings as errors, then run the whole test suite. With
# PTERYLA_TEST_FULL=1, then the suite again under ASan+UBSan (tools/sanitize.sh, ./build-asan) and each
# reader's fuzz target for PTERYLA_FUZZ_SECONDS (default 60) s (tools/fuzz.sh, ./build-fuzz): about 25
# more minutes on 2 cores, not yet measured cold on a fresh machine, so CI does not run them yet.
set -euo pipefail
cd "$(dirname "$0")/.."
PTERYLA_CMAKE_ARGS="-DPTERYLA_WERROR=ON ${PTERYLA_CMAKE_ARGS:-}" bash tools/build.sh
cmake -S . -B build -DPTERYLA_WERROR=ON >/dev/null
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)"
if [ "${PTERYLA_TEST_FULL:-0}" = 1 ]; then
  bash tools/sanitize.sh
  bash tools/fuzz.sh "${PTERYLA_FUZZ_SECONDS:-60}"
fi
