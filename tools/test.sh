#!/usr/bin/env bash
# README command 2 (and .ci/run): every test, the way CI runs them.
#  1. The whole suite but the corpus and the `heavy` tests, built with AddressSanitizer +
#     UndefinedBehaviorSanitizer and warnings as errors (tools/sanitize.sh, ./build-asan): a memory error,
#     leak or undefined behaviour fails the test. The single-node Slurm test runs there too (bootstrap
#     --slurm installs slurm-wlm and munge).
#  2. In the Release build (./build, -Werror), only the targets these need: the `heavy` tests (label
#     heavy, target pteryla_heavy_tests: scene-scale tests of 20-80 s each under the sanitizers, listed
#     with HEAVY in tests/*/CMakeLists.txt) and, where ../shared/meshes exists, the real-mesh corpus tests
#     (label corpus) with the Release CLI: each feathers 3,000 follicles, too slow under the sanitizers.
#     Only the bare variants: a minimal scene is the same coat (label corpus_minimal; a unit test holds
#     that), so running it too would double the phase for nothing.
#  3. Each reader's libFuzzer target for PTERYLA_FUZZ_SECONDS (default 30) s from its seed corpus
#     (tools/fuzz.sh, clang, ./build-fuzz).
# PTERYLA_TEST_RELEASE=1 also builds everything in ./build and runs the whole suite there. Each phase
# prints its wall time. Cost: README, "Sanitizers and fuzzing".
set -euo pipefail
cd "$(dirname "$0")/.."
phase_start=$SECONDS
phase() {  # phase NAME: the time since the previous phase ended
  echo "== test.sh: $1 took $((SECONDS - phase_start)) s (total $SECONDS s)"
  phase_start=$SECONDS
}
bash tools/bootstrap.sh --fuzz --slurm
phase bootstrap
bash tools/sanitize.sh -LE "corpus|heavy"
phase "sanitized build and suite"
if [ "${PTERYLA_TEST_RELEASE:-0}" = 1 ]; then
  bash tools/build.sh
  ctest --test-dir build --output-on-failure -j"$(nproc)"
  phase "Release build and suite"
else
  PTERYLA_BUILD_TARGETS="pteryla pteryla_heavy_tests" bash tools/build.sh
  ctest --test-dir build --output-on-failure -j"$(nproc)" -L "corpus|heavy" -LE corpus_minimal
  phase "Release CLI, heavy tests and corpus"
fi
bash tools/fuzz.sh "${PTERYLA_FUZZ_SECONDS:-30}"
phase fuzzing
