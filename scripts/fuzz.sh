#!/usr/bin/env bash
# Fuzzes every parser with libFuzzer (tests/fuzz): builds the fuzz targets with clang, the libraries
# instrumented for coverage, AddressSanitizer and UBSan, into build-fuzz/; runs each target for
# SECONDS (default 300) from its corpus; merges the inputs that reached new code into
# tests/fuzz/corpus/<target>/, minimised; and prints each target's executions and coverage.
# Inputs that crash, leak or hang are kept in build-fuzz/findings/<target>/; a finding fails the run.
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
status=0
printf '%-16s %12s %8s %8s %8s %s\n' target executions exec/s cov ft findings > build-fuzz/summary.txt
for t in "${targets[@]}"; do
  program=build-fuzz/tests/fuzz/fuzz_$t
  corpus=tests/fuzz/corpus/$t
  work=build-fuzz/new/$t
  findings=build-fuzz/findings/$t
  mkdir -p "$work" "$findings" build-fuzz/logs
  echo "fuzz: $t for ${seconds}s"
  # -fork keeps going after a finding, so that one run reports every kind of failure it meets.
  "$program" -max_total_time="$seconds" -rss_limit_mb=2048 -malloc_limit_mb=2048 -max_len=16384 -timeout=20 -fork=1 \
    -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1 -print_funcs=0 -artifact_prefix="$findings/" \
    "$work" "$corpus" > build-fuzz/logs/$t.log 2>&1 || true
  "$program" -merge=1 "$corpus" "$work" >> build-fuzz/logs/$t.merge.log 2>&1
  # The fork mode's last progress line: "#RUNS: cov: C ft: F corp: N exec/s: E oom/timeout/crash: ..."
  last=$(grep -E '^#[0-9]+:' build-fuzz/logs/$t.log | tail -1 || true)
  runs=$(sed -E 's/^#([0-9]+):.*/\1/' <<< "$last")
  speed=$(grep -oE 'exec/s: [0-9]+' <<< "$last" | grep -oE '[0-9]+' || true)
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
