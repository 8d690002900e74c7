#!/usr/bin/env bash
# The GPU check, run on a lent GPU machine from the bundle that scripts/gpu_bundle.sh built here. It
# must settle the question in one short window, so it works to a deadline and always reports:
#
#   preflight    the GPU, driver and glibc; every carried binary's libraries (ldd); whether CUDA runs
#                at all (one cuda test that needs a GPU). No GPU: verdict NO-GPU, nothing else runs.
#   steps        in order of value, each within the time left: the cuda-labelled tests; voxfuse_bench
#                with --device cuda on the carried teddy depth pack and on the synthetic room
#                (tracked, then given poses on the hash and the dense index); teddy's poses and mesh
#                against the CPU reference the bundle carries (made on the build machine, so no
#                device time goes to CPU work); last, if time is left, the cuda tests under
#                compute-sanitizer's memcheck. A step that cannot get its least useful time is skipped
#                and named; a running step is cut at its own limit or at the deadline (timeout -k).
#   summary      written to $OUT as the steps finish, and printed by a trap however the script ends
#                (done, killed, timed out): per-step results, failed tests, per-stage medians, parity.
#   verdict      one line, `GPU CHECK: PASS|FAIL|NO-GPU ...`; exit 0, 1 and 2 respectively. NO-GPU
#                also when every cuda test skipped.
#
#   ./gpu_bundle/gpu_check.sh [--deadline SECONDS] [--bundle DIR]    (default 420 s; logs to $OUT or /tmp)
#
# On a machine without a GPU (this one) the same command is a dry run that ends NO-GPU in seconds;
# tests/cli/gpu_check_dry_run.py runs it so. Needs bash, coreutils' timeout and python3 (the summary;
# without it a plain one).
set -uo pipefail

deadline_s=420
bundle=""
while [ $# -gt 0 ]; do
  case "$1" in
    --deadline) deadline_s=${2:?--deadline needs a number of seconds}; shift 2 ;;
    --bundle) bundle=${2:?--bundle needs a directory}; shift 2 ;;
    -h|--help) sed -n '2,23p' "$0"; exit 0 ;;
    *) echo "gpu_check: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
case "$deadline_s" in ''|*[!0-9]*) echo "gpu_check: --deadline wants whole seconds, not '$deadline_s'" >&2; exit 2 ;; esac
here=$(cd "$(dirname "$0")" && pwd)
if [ -z "$bundle" ]; then
  if [ -d "$here/bin" ]; then bundle=$here; else bundle=gpu_bundle; fi
fi
bundle=$(cd "$bundle" 2>/dev/null && pwd) || { echo "gpu_check: no bundle at '$bundle' (build it with scripts/gpu_bundle.sh)" >&2; exit 2; }
out=${OUT:-/tmp/voxfuse_gpu_check}
mkdir -p "$out"
status="$out/status.txt"     # one line per step: NAME RESULT SECONDS
summary="$out/summary.txt"   # what the trap prints, written as it goes
: >"$status"
: >"$summary"
SECONDS=0
interrupted=""
no_gpu=""
gpu_name="unknown GPU"
note() { echo "$*" | tee -a "$summary"; }
left() { echo $((deadline_s - SECONDS)); }

export LD_LIBRARY_PATH="$bundle/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"

all_steps=(cuda_tests engine_cuda_tests teddy_cuda bench_cuda_tracked bench_cuda_hash bench_cuda_dense teddy_parity memcheck_cuda_tests memcheck_engine_tests)
step_pid=""
finish() {
  trap - EXIT INT TERM HUP
  if [ -n "$step_pid" ]; then  # a step still running: timeout passes the signal on to it
    kill -TERM "$step_pid" 2>/dev/null
    wait "$step_pid" 2>/dev/null
    echo "${current_step:-step} interrupted $((SECONDS - ${step_started:-0}))" >>"$status"
  fi
  local verdict failed skipped passed name
  for name in "${all_steps[@]}"; do  # steps an interruption or an early end kept from running
    grep -q "^$name " "$status" || echo "$name not-reached 0" >>"$status"
  done
  # What the steps left: machine-readable lines first, then the tables.
  failed=$(awk '$2 != "ok" && $2 != "skipped" && $2 != "not-reached" {printf "%s%s (%s)", sep, $1, $2; sep=", "}' "$status")
  skipped=$(awk '$2 == "skipped" {printf "%s%s", sep, $1; sep=", "}' "$status")
  passed=$(awk '$2 == "ok"' "$status" | wc -l)
  if command -v python3 >/dev/null 2>&1; then
    timeout -k 5 30 python3 "$bundle/gpu_check_summary.py" "$out" "$bundle" >>"$summary" 2>&1 || echo "(summary script failed)" >>"$summary"
  fi
  if [ -n "$interrupted" ]; then
    verdict="FAIL (interrupted by $interrupted after ${SECONDS} s${failed:+; failed: $failed})"
  elif [ -n "$no_gpu" ]; then
    verdict="NO-GPU ($no_gpu)"
  elif [ -n "$failed" ]; then
    verdict="FAIL (failed: $failed${skipped:+; skipped: $skipped})"
  else
    verdict="PASS ($passed steps${skipped:+; skipped for time: $skipped})"
  fi
  verdict="$verdict; bundle $(cat "$bundle/commit.txt" 2>/dev/null || echo '?'), $gpu_name, ${SECONDS} s of a ${deadline_s} s deadline"
  echo "GPU CHECK: $verdict" >>"$summary"
  echo "GPU CHECK: $verdict" >"$out/verdict.txt"
  # The steps' lines were printed as they ran; the tables and the verdict now.
  sed -n '/^==== VoxFuse GPU check summary/,$p' "$summary"
  grep -q '^==== VoxFuse GPU check summary' "$summary" || tail -n 1 "$summary"
  case "$verdict" in PASS*) exit 0 ;; NO-GPU*) exit 2 ;; *) exit 1 ;; esac
}
trap 'interrupted=SIGINT; finish' INT
trap 'interrupted=SIGTERM; finish' TERM
trap 'interrupted=SIGHUP; finish' HUP
trap finish EXIT

# step NAME LEAST MOST COMMAND...: runs COMMAND within min(MOST, time left) seconds, output in
# $out/NAME.log; skipped (and named) when less than LEAST seconds are left.
step() {
  local name=$1 least=$2 most=$3
  shift 3
  local remaining limit started rc result
  remaining=$(left)
  if [ "$remaining" -lt "$least" ]; then
    echo "$name skipped 0" >>"$status"
    note "== $name: skipped (needs at least ${least} s, ${remaining} s left)"
    return 0
  fi
  limit=$((most < remaining ? most : remaining))
  note "== $name (limit ${limit} s): $*"
  started=$SECONDS
  current_step=$name
  step_started=$started
  # In the background and waited for: bash runs a trap only between commands, and `wait` is one it
  # interrupts, so a signal is answered at once, not after the step's own limit.
  timeout -k 10 "$limit" "$@" >"$out/$name.log" 2>&1 &
  step_pid=$!
  wait "$step_pid"
  rc=$?
  step_pid=""
  case "$rc" in
    0) result=ok ;;
    124|137) result="timed-out-after-${limit}s" ;;
    *) result="exit-$rc" ;;
  esac
  echo "$name $result $((SECONDS - started))" >>"$status"
  note "   $result in $((SECONDS - started)) s; $(tail -n 1 "$out/$name.log" 2>/dev/null | cut -c1-160)"
}
skip_rest() {  # skip_rest REASON NAME...: names the steps that will not run
  local reason=$1
  shift
  for name in "$@"; do echo "$name skipped 0" >>"$status"; done
  note "== skipped ($reason): $*"
}

# ---- Preflight ----
note "== bundle of commit $(cat "$bundle/commit.txt" 2>/dev/null || echo '?'), deadline ${deadline_s} s, logs in $out"
if command -v nvidia-smi >/dev/null 2>&1; then
  smi=$(timeout -k 2 15 nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>&1 | head -n 1)
  note "   GPU, driver, memory: $smi"
  gpu_name=$(echo "$smi" | cut -d, -f1)
else
  note "   nvidia-smi: not found"
fi
note "   glibc: $(getconf GNU_LIBC_VERSION 2>/dev/null || ldd --version 2>&1 | head -n 1)"
# Every carried binary and library must find its libraries: the machine's own C++ runtime first, the
# bundled copies (fallback/) only for what it lacks.
missing_libs() { for f in "$bundle"/bin/* "$bundle"/lib/*.so*; do [ -f "$f" ] && ldd "$f" 2>/dev/null | grep "not found" | sed "s|^|$(basename "$f"): |"; done; }
if [ -n "$(missing_libs)" ]; then export LD_LIBRARY_PATH="$LD_LIBRARY_PATH:$bundle/fallback"; note "   libraries: using the bundled fallbacks for $(missing_libs | awk '{print $2}' | sort -u | tr '\n' ' ')"; fi
unresolved=$(missing_libs)
if [ -n "$unresolved" ]; then
  note "   libraries still not found:"
  note "$unresolved"
  echo "preflight exit-missing-libraries 0" >>"$status"
  skip_rest "a binary cannot load" "${all_steps[@]}"
  exit 1
fi
note "   libraries: every carried binary resolves (ldd)"
probe=$(timeout -k 5 60 "$bundle/bin/voxfuse_cuda_tests" --gtest_filter='CudaDeviceTest.ReadAndWriteOneElement' 2>&1)
if ! echo "$probe" | grep -q '\[  PASSED  \] 1 test'; then
  no_gpu="CUDA is unusable here: $(echo "$probe" | grep -m 1 -i -E 'no usable|skipped|error|fail' | cut -c1-160)"
  note "   CUDA probe: $no_gpu"
  skip_rest "no GPU" "${all_steps[@]}"
  exit 2
fi
note "   CUDA probe: a cuda test ran on the GPU"
echo "preflight ok $SECONDS" >>"$status"

# ---- Steps, in order of value ----
step cuda_tests 30 150 "$bundle/bin/voxfuse_cuda_tests" --gtest_brief=1 --gtest_output="xml:$out/cuda_tests.xml"
step engine_cuda_tests 20 120 "$bundle/bin/voxfuse_core_tests" --gtest_brief=1 --gtest_filter='*cuda*' --gtest_output="xml:$out/engine_cuda_tests.xml"
# Every cuda test skipped: the GPU was not used after all (an NO-GPU run must not read as a pass).
ran=$(cat "$out"/cuda_tests.xml "$out"/engine_cuda_tests.xml 2>/dev/null | grep -c '<testcase .*status="run"' || true)
skips=$(cat "$out"/cuda_tests.xml "$out"/engine_cuda_tests.xml 2>/dev/null | grep -c '<skipped' || true)
if [ -f "$out/cuda_tests.xml" ] && [ "$ran" -gt 0 ] && [ "$ran" -le "$skips" ]; then
  no_gpu="every one of the $ran cuda tests skipped"
  skip_rest "no GPU" teddy_cuda bench_cuda_tracked bench_cuda_hash bench_cuda_dense teddy_parity memcheck_cuda_tests memcheck_engine_tests
  exit 2
fi
cd "$out"
work=$(mktemp -d)  # teddy's mesh (70 MB) stays out of $OUT, which comes back
if [ -d "$bundle/teddy_pack" ]; then
  # Depth only (the pack has no colour): ren, as the CPU reference was made.
  step teddy_cuda 20 90 "$bundle/bin/voxfuse_bench" "$bundle/teddy_pack" --device cuda --tracker ren --voxel s --mesh --repeats 1 \
    --json teddy_cuda.json --trajectory teddy_cuda_trajectory.txt --mesh-out "$work/teddy_cuda_mesh.ply"
else
  skip_rest "the bundle has no teddy pack" teddy_cuda
fi
frames=${VOXFUSE_GPU_CHECK_FRAMES:-80}
step bench_cuda_tracked 15 60 "$bundle/bin/voxfuse_bench" "synthetic:$frames" --device cuda --render --json bench_cuda_tracked.json
step bench_cuda_hash 15 60 "$bundle/bin/voxfuse_bench" "synthetic:$frames" --device cuda --poses groundtruth --mesh --cloud --repeats 5 --json bench_cuda_hash.json
step bench_cuda_dense 15 60 "$bundle/bin/voxfuse_bench" "synthetic:$frames" --device cuda --poses groundtruth --index dense --mesh --cloud --repeats 5 --json bench_cuda_dense.json
if [ -f "$bundle/reference/teddy_cpu.json" ] && [ -f teddy_cuda.json ]; then
  cp "$bundle/reference/teddy_cpu.json" "$bundle/reference/teddy_cpu_trajectory.txt" .
  cp teddy_cuda.json teddy_cuda_trajectory.txt "$work/" 2>/dev/null
  step teddy_parity 5 60 python3 "$bundle/device_parity.py" "$bundle/reference/teddy_cpu" "$work/teddy_cuda"
else
  skip_rest "no CPU reference or no teddy run" teddy_parity
fi
rm -rf "$work"
# Memcheck slows kernels many times over: two voxel types (plain, colour) of each typed suite, the
# tracked pipeline and the per-device engine tests. No leak check: the test programs exit without
# destroying their CUDA context, which a leak report needs to mean anything.
sanitizer=$(command -v compute-sanitizer || ls /usr/local/cuda/bin/compute-sanitizer 2>/dev/null || true)
if [ -n "$sanitizer" ]; then
  memcheck=("$sanitizer" --tool memcheck --error-exitcode 3)
  step memcheck_cuda_tests 60 150 "${memcheck[@]}" "$bundle/bin/voxfuse_cuda_tests" --gtest_brief=1 \
    --gtest_filter='*/0.*:*/2.*:Indexes/*:EngineCudaCapacity*:CudaDevice*'
  step memcheck_engine_tests 60 120 "${memcheck[@]}" "$bundle/bin/voxfuse_core_tests" --gtest_brief=1 --gtest_filter='*cuda*'
else
  skip_rest "no compute-sanitizer" memcheck_cuda_tests memcheck_engine_tests
fi
exit 0
