#!/usr/bin/env bash
# Fuzzes every parser with libFuzzer (tests/fuzz): builds the fuzz targets with clang, the libraries
# instrumented for coverage, AddressSanitizer and UBSan, into build-fuzz/; runs each target for
# SECONDS (default 300) from its corpus; merges the inputs that reached new code into
# tests/fuzz/corpus/<target>/, minimised; and prints each target's executions and coverage.
# Inputs that crash, leak or hang are kept in build-fuzz/findings/<target>/; a finding fails the run.
# One target at a time, one process each: two cores are shared with the build.
#   ./scripts/fuzz.sh [SECONDS] [TARGET...]     e.g. ./scripts/fuzz.sh 600 calib map_file
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-300}
shift || true
./scripts/install_deps.sh clang libclang-rt-14-dev libomp-14-dev

# -O1 with line tables: fast enough to fuzz, readable stacks, asserts kept, and a build that takes
# half the time of -O2 -g on two cores.
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=Fuzz -DCMAKE_CXX_FLAGS_FUZZ="-O1 -gline-tables-only" \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DVOXFUSE_FUZZ=ON -DVOXFUSE_CUDA=OFF -DVOXFUSE_PYTHON=OFF -DVOXFUSE_BUILD_APPS=OFF -DVOXFUSE_BUILD_TESTS=OFF \
  -DVOXFUSE_BUILD_BENCH=OFF -DVOXFUSE_OPENNI2=OFF
cmake --build build-fuzz -j2

targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  for program in build-fuzz/tests/fuzz/fuzz_*; do targets+=("${program##*/fuzz_}"); done
fi

# Third-party libraries that keep allocations until exit are not VoxFuse's leaks.
export LSAN_OPTIONS="suppressions=$PWD/tests/io/lsan_third_party.supp"
export UBSAN_OPTIONS="print_stacktrace=1"
# One CPU thread: fuzzing runs one input at a time, and (OpenMP's) spinning threads on two shared cores
# turned 10 ms inputs into 26 s timeouts.
export VOXFUSE_NUM_THREADS=1
status=0
printf '%-16s %12s %8s %8s %8s %s\n' target executions exec/s cov ft findings > build-fuzz/summary.txt
for t in "${targets[@]}"; do
  program=build-fuzz/tests/fuzz/fuzz_$t
  corpus=tests/fuzz/corpus/$t
  work=build-fuzz/new/$t
  findings=build-fuzz/findings/$t
  mkdir -p "$work" "$findings" build-fuzz/logs
  echo "fuzz: $t for ${seconds}s"
  # One process (libFuzzer's fork mode is ten times slower); after a finding it starts again from
  # the corpus for the time left, at most five times, so that one finding does not end the run.
  deadline=$(( $(date +%s) + seconds ))
  # Maps with keyframes or submaps start at 25-27 KB (seed_hash_s_keyframes, seed_submaps_hash_s).
  max_len=16384
  [ "$t" != map_file ] || max_len=32768
  : > build-fuzz/logs/$t.log
  for attempt in 1 2 3 4 5 6; do
    left=$(( deadline - $(date +%s) ))
    [ "$left" -gt 5 ] || break
    "$program" -max_total_time="$left" -rss_limit_mb=2048 -malloc_limit_mb=2048 -max_len=$max_len -timeout=20 -print_final_stats=1 \
      -artifact_prefix="$findings/" "$work" "$corpus" >> build-fuzz/logs/$t.log 2>&1 || true
  done
  "$program" -merge=1 "$corpus" "$work" >> build-fuzz/logs/$t.merge.log 2>&1
  # Executions summed over the attempts; coverage from the last progress line.
  runs=$(grep -oE 'stat::number_of_executed_units: [0-9]+' build-fuzz/logs/$t.log | awk '{ s += $2 } END { print s }')
  last=$(grep -E '^#[0-9]+' build-fuzz/logs/$t.log | grep -E 'cov: ' | tail -1 || true)
  speed=$(grep -oE 'exec/s:? [0-9]+' <<< "$last" | grep -oE '[0-9]+' || true)
  cov=$(grep -oE 'cov: [0-9]+' <<< "$last" | grep -oE '[0-9]+' || true)
  ft=$(grep -oE 'ft: [0-9]+' <<< "$last" | grep -oE '[0-9]+' || true)
  found=$(find "$findings" -type f | wc -l)
  printf '%-16s %12s %8s %8s %8s %s\n' "$t" "${runs:-?}" "${speed:-?}" "${cov:-?}" "${ft:-?}" "$found" >> build-fuzz/summary.txt
  if [ "$found" -gt 0 ]; then status=1; fi
done
cat build-fuzz/summary.txt
if [ "$status" -ne 0 ]; then
  echo "fuzz: findings in build-fuzz/findings/ (reproduce: build-fuzz/tests/fuzz/fuzz_TARGET FILE)"
fi
exit $status
