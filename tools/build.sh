#!/usr/bin/env bash
# Configures and builds pteryla (Release) into ./build. Used by the README's two commands.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/bootstrap.sh
GEN=()
command -v ninja >/dev/null && GEN=(-G Ninja)
if [ ! -f build/CMakeCache.txt ]; then
  cmake -S . -B build "${GEN[@]}" -DCMAKE_BUILD_TYPE=Release ${PTERYLA_CMAKE_ARGS:-} >/dev/null
fi
cmake --build build -j"$(nproc)"
