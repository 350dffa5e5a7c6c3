#!/usr/bin/env bash
# Regenerates docs/gallery.md and docs/gallery/*.png: renders, checks and benchmarks every bundled scene
# with the pteryla CLI (see tools/scenes/gallery.py). Options are passed on, e.g. --only wing,crest --no-bench.
# BUILD_DIR (default build) is the CMake build directory to build the CLI in.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
if [ ! -f "$BUILD_DIR/build.ninja" ] && [ ! -f "$BUILD_DIR/Makefile" ]; then
  cmake -S . -B "$BUILD_DIR" -G Ninja -DPTERYLA_BUILD_VIEWER=OFF
fi
cmake --build "$BUILD_DIR" --target pteryla
python3 tools/scenes/gallery.py --pteryla "$BUILD_DIR/apps/pteryla/pteryla" "$@"
