#!/usr/bin/env bash
# README command 2 (and .ci/run): every test, the way CI runs them.
#  1. The whole suite built with AddressSanitizer + UndefinedBehaviorSanitizer and warnings as errors
#     (tools/sanitize.sh, ./build-asan): a memory error, leak or undefined behaviour fails the test.
#  2. The real-mesh corpus tests (label corpus; only where ../shared/meshes exists) in the Release build
#     (./build, -Werror): each feathers 3,000 follicles, too slow under the sanitizers.
#  3. Each reader's libFuzzer target for PTERYLA_FUZZ_SECONDS (default 60) s from its seed corpus
#     (tools/fuzz.sh, clang, ./build-fuzz).
# PTERYLA_TEST_RELEASE=1 also runs the whole suite in the Release build. Cost: README, "Sanitizers and fuzzing".
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/bootstrap.sh --fuzz
bash tools/sanitize.sh -LE corpus
if [ "${PTERYLA_TEST_RELEASE:-0}" = 1 ] || [ -d ../shared/meshes ]; then
  bash tools/build.sh
  if [ "${PTERYLA_TEST_RELEASE:-0}" = 1 ]; then
    ctest --test-dir build --output-on-failure -j"$(nproc)"
  else
    ctest --test-dir build --output-on-failure -j"$(nproc)" -L corpus
  fi
fi
bash tools/fuzz.sh "${PTERYLA_FUZZ_SECONDS:-60}"
