#!/usr/bin/env bash
# README command 2 (and .ci/run): build with warnings as errors, then run the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
PTERYLA_CMAKE_ARGS="-DPTERYLA_WERROR=ON ${PTERYLA_CMAKE_ARGS:-}" bash tools/build.sh
cmake -S . -B build -DPTERYLA_WERROR=ON >/dev/null
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)"
