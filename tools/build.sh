#!/usr/bin/env bash
# Configures and builds pteryla (Release, warnings as errors) into ./build. README command 1 uses it;
# command 2 (tools/test.sh) uses it for the heavy and the real-mesh corpus tests.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/bootstrap.sh
GEN=()
command -v ninja >/dev/null && GEN=(-G Ninja)
[ -f build/CMakeCache.txt ] && GEN=()
cmake -S . -B build "${GEN[@]}" -DCMAKE_BUILD_TYPE=Release -DPTERYLA_WERROR=ON ${PTERYLA_CMAKE_ARGS:-} >/dev/null
# PTERYLA_BUILD_TARGETS="a b": only those targets (tools/test.sh builds just the CLI and the
# executables of the heavy tests).
cmake --build build -j"$(nproc)" ${PTERYLA_BUILD_TARGETS:+--target $PTERYLA_BUILD_TARGETS}
