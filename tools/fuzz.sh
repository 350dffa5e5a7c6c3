#!/usr/bin/env bash
# Fuzzes the file readers (issue #21 part 7): builds the libFuzzer targets of tests/fuzz with clang into
# ./build-fuzz (PTERYLA_FUZZ=ON: -fsanitize=fuzzer,address,undefined) and runs each for SECONDS (default
# 60) from its checked-in seed corpus tests/fuzz/corpus/<target>/. Prints executions per second per target;
# exits non-zero when any target finds a crash, a leak, undefined behaviour, a timeout or an out-of-memory.
# Findings are written to build-fuzz/findings/<target>/ (reproduce: build-fuzz/tests/fuzz/fuzz_<target> FILE).
# New inputs the fuzzer finds go to build-fuzz/corpus/<target>/, never into the source tree.
#
#   bash tools/fuzz.sh [SECONDS] [TARGET...]        TARGET: scene feather skeleton mesh (default: all)
#   PTERYLA_FUZZ_JOBS=N   targets fuzzed at once (default: nproc; each target uses one core)
set -euo pipefail
cd "$(dirname "$0")/.."
SECS=${1:-60}
[ $# -gt 0 ] && shift
TARGETS=("$@")
[ ${#TARGETS[@]} -gt 0 ] || TARGETS=(scene feather skeleton mesh)
JOBS=${PTERYLA_FUZZ_JOBS:-$(nproc)}

# Longest input each target may grow (about the largest seed, so it stays a reader test).
declare -A MAXLEN=([scene]=12288 [feather]=4096 [skeleton]=4096 [mesh]=4096)

bash tools/bootstrap.sh --fuzz
export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$PWD}
if [ ! -f build-fuzz/CMakeCache.txt ]; then
  # -O1 -g1 and assertions on (no NDEBUG): the usual fuzzing trade-off between speed and checks.
  CC=clang-14 CXX=clang++-14 cmake -S . -B build-fuzz -G Ninja -DPTERYLA_FUZZ=ON \
    -DPTERYLA_BUILD_TESTS=OFF -DPTERYLA_BUILD_VIEWER=OFF -DPTERYLA_BUILD_BENCHMARKS=OFF \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1" \
    "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O1 -g1" >/dev/null
fi
cmake --build build-fuzz -j"$(nproc)" --target "${TARGETS[@]/#/fuzz_}"

# The symbolizer gives the findings' stacks file:line.
[ -x /usr/lib/llvm-14/bin/llvm-symbolizer ] && export ASAN_SYMBOLIZER_PATH=/usr/lib/llvm-14/bin/llvm-symbolizer
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:check_initialization_order=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

run_target() {
  local t=$1
  mkdir -p "build-fuzz/corpus/$t" "build-fuzz/findings/$t"
  # -timeout: one input taking >10 s is a hang; -rss_limit_mb/-malloc_limit_mb: a reader allocating
  # >2 GB for a small file is a finding (OOM), not something to wait for.
  "build-fuzz/tests/fuzz/fuzz_$t" -max_total_time="$SECS" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=2048 \
    -max_len="${MAXLEN[$t]}" -print_final_stats=1 -artifact_prefix="build-fuzz/findings/$t/" \
    "build-fuzz/corpus/$t" "tests/fuzz/corpus/$t" >"build-fuzz/fuzz_$t.log" 2>&1
}

status=0
declare -A RC
pids=()
for t in "${TARGETS[@]}"; do
  [ -d "tests/fuzz/corpus/$t" ] || { echo "fuzz: no seed corpus tests/fuzz/corpus/$t" >&2; exit 2; }
  while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do sleep 1; done
  echo "fuzz: $t for ${SECS}s" >&2
  ( run_target "$t" ) &
  pids+=("$!:$t")
done
for pt in "${pids[@]}"; do
  rc=0
  wait "${pt%%:*}" || rc=$?
  RC[${pt#*:}]=$rc
done
for t in "${TARGETS[@]}"; do
  log="build-fuzz/fuzz_$t.log"
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  if [ "${RC[$t]}" -eq 0 ]; then
    printf 'fuzz_%-9s ok        %8s exec/s  %10s runs in %ss\n' "$t" "${rate:-?}" "${execs:-?}" "$SECS"
  else
    status=1
    printf 'fuzz_%-9s FINDING   %8s exec/s  (exit %s), see %s and build-fuzz/findings/%s/\n' \
      "$t" "${rate:-?}" "${RC[$t]}" "$log" "$t"
    grep -E -A40 '^==[0-9]+==ERROR|runtime error|deadly signal|Timeout|out-of-memory|uncaught exception|terminate called' "$log" | head -60 >&2 || tail -40 "$log" >&2
  fi
done
exit $status
