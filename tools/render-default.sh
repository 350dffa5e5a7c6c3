#!/usr/bin/env bash
# README command 1: build everything, then render the bundled default scene to out/bird.png.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/build.sh
mkdir -p out
./build/apps/pteryla/pteryla render data/scenes/bird.json --out out/bird.png
echo "rendered: $(pwd)/out/bird.png"
