#!/usr/bin/env bash
# Builds the unit tests, the command-line programs and the corpus replays with AddressSanitizer and
# UBSan (g++, without CUDA) into build-asan/ and runs the tests labelled unit there: any memory error,
# leak or undefined behaviour fails its test. Too slow for .ci/run on two cores; run it before a
# release and after changing a parser or an engine's memory handling.
#   ./scripts/sanitize_tests.sh [CTEST ARGUMENTS...]     e.g. ./scripts/sanitize_tests.sh -R 'CalibIO|fuzz'
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install_deps.sh
# -O1 with line tables: readable reports, and a build far shorter than -O2 -g on two cores. Only
# what the unit tests run is built (no viewer, no data or GPU tests).
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Asan -DCMAKE_CXX_FLAGS_ASAN="-O1 -g1" -DVOXFUSE_SANITIZE=ON -DVOXFUSE_CUDA=OFF \
  -DVOXFUSE_PYTHON=OFF
replays=$(ninja -C build-asan -t targets all | grep -o '^voxfuse_fuzz_replay_[a-z_]*' | sort -u)
cmake --build build-asan -j2 --target voxfuse_core_tests voxfuse_unit_tests voxfuse_cli voxfuse_bench voxfuse_synth $replays
# Third-party libraries that keep allocations until exit are not VoxFuse's leaks.
export LSAN_OPTIONS="suppressions=$PWD/tests/io/lsan_third_party.supp"
export ASAN_OPTIONS="detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
ctest --test-dir build-asan -L unit --output-on-failure -j2 "$@"
