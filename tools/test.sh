#!/usr/bin/env bash
# README command 2 (and .ci/run): every test, the way CI runs them.
#  1. The whole suite built with AddressSanitizer + UndefinedBehaviorSanitizer and warnings as errors
#     (tools/sanitize.sh, ./build-asan): a memory error, leak or undefined behaviour fails the test.
#     The single-node Slurm test runs there too (bootstrap --slurm installs slurm-wlm and munge).
#  2. The real-mesh corpus tests (label corpus; only where ../shared/meshes exists) with the Release CLI
#     (./build, -Werror; only the `pteryla` target is built for them): each feathers 3,000 follicles, too
#     slow under the sanitizers. Only the bare variants: a minimal scene is the same coat (label
#     corpus_minimal; a unit test holds that), so running it too would double the phase for nothing.
#  3. Each reader's libFuzzer target for PTERYLA_FUZZ_SECONDS (default 60) s from its seed corpus
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
bash tools/sanitize.sh -LE corpus
phase "sanitized build and suite"
if [ "${PTERYLA_TEST_RELEASE:-0}" = 1 ]; then
  bash tools/build.sh
  ctest --test-dir build --output-on-failure -j"$(nproc)"
  phase "Release build and suite"
elif [ -d ../shared/meshes ]; then
  PTERYLA_BUILD_TARGETS=pteryla bash tools/build.sh
  ctest --test-dir build --output-on-failure -j"$(nproc)" -L corpus -LE corpus_minimal
  phase "Release CLI and corpus"
fi
bash tools/fuzz.sh "${PTERYLA_FUZZ_SECONDS:-60}"
phase fuzzing
