#!/usr/bin/env bash
# The GPU check, run on a lent GPU machine from the bundle that scripts/gpu_bundle.sh built here:
# the cuda-labelled tests (what only the GPU runs, and CPU-CUDA parity), voxfuse_bench with
# --device cuda on synthetic frames rendered in memory (no image files or codecs needed), and, when
# the bundle carries teddy's depth pack, the tracked run on it on both devices compared frame by frame
# and mesh by mesh (device_parity.py); last, where compute-sanitizer runs, the cuda tests once more
# under its memcheck (out-of-bounds and misaligned accesses, hardware exceptions, failed CUDA
# calls); then one summary. Needs nothing on that machine but the NVIDIA driver and python3; takes a
# few minutes (VOXFUSE_GPU_CHECK_MEMCHECK=0 leaves the memcheck out).
#
#   ./gpu_bundle/gpu_check.sh        (from the repository root; logs, XML and JSON go to $OUT or /tmp)
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
if [ -x "$here/bin/voxfuse_bench" ]; then bundle=$here; else bundle=$(cd "${1:-gpu_bundle}" && pwd); fi
out=${OUT:-/tmp/voxfuse_gpu_check}
mkdir -p "$out"
export LD_LIBRARY_PATH="$bundle/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
# The machine's own C++ runtime first; the bundled copies only for what it lacks.
if ldd "$bundle/bin/voxfuse_bench" | grep -q "not found"; then export LD_LIBRARY_PATH="$LD_LIBRARY_PATH:$bundle/fallback"; fi
frames=${VOXFUSE_GPU_CHECK_FRAMES:-80}

step() {  # step NAME SECONDS COMMAND...: runs with a time limit, output to $out/NAME.log
  local name=$1 limit=$2
  shift 2
  echo "== $name: $*"
  timeout "$limit" "$@" >"$out/$name.log" 2>&1
  local rc=$?
  echo "$name $rc" >>"$out/status.txt"
  tail -n 4 "$out/$name.log"
}

: >"$out/status.txt"
echo "== bundle of commit $(cat "$bundle/commit.txt" 2>/dev/null); $(nvidia-smi -L 2>&1 | head -n 1)"
step cuda_tests 180 "$bundle/bin/voxfuse_cuda_tests" --gtest_brief=1 --gtest_output="xml:$out/cuda_tests.xml"
step engine_cuda_tests 180 "$bundle/bin/voxfuse_core_tests" --gtest_brief=1 --gtest_filter='*cuda*' --gtest_output="xml:$out/engine_cuda_tests.xml"
cd "$out"
step bench_cuda_hash 120 "$bundle/bin/voxfuse_bench" "synthetic:$frames" --device cuda --poses groundtruth --mesh --cloud --repeats 5 --json bench_cuda_hash.json
step bench_cuda_dense 120 "$bundle/bin/voxfuse_bench" "synthetic:$frames" --device cuda --poses groundtruth --index dense --mesh --cloud --repeats 5 --json bench_cuda_dense.json
step bench_cuda_tracked 120 "$bundle/bin/voxfuse_bench" "synthetic:$frames" --device cuda --render --json bench_cuda_tracked.json
step bench_cpu_hash 180 "$bundle/bin/voxfuse_bench" "synthetic:$frames" --device cpu --poses groundtruth --mesh --cloud --repeats 3 --json bench_cpu_hash.json
if [ -d "$bundle/teddy_pack" ]; then
  # The meshes (70 MB each) stay out of $OUT, which comes back.
  work=$(mktemp -d)
  for dev in cpu cuda; do
    # Depth only (the pack has no colour): ren, as named in the summary, whatever the default tracker.
    step teddy_$dev 180 "$bundle/bin/voxfuse_bench" "$bundle/teddy_pack" --device $dev --tracker ren --voxel s --mesh --repeats 1 --json teddy_$dev.json \
      --trajectory "$work/teddy_${dev}_trajectory.txt" --mesh-out "$work/teddy_${dev}_mesh.ply"
    cp "teddy_$dev.json" "$work/" 2>/dev/null
  done
  step teddy_parity 120 python3 "$bundle/device_parity.py" "$work/teddy_cpu" "$work/teddy_cuda"
  cp "$work"/teddy_*_trajectory.txt . 2>/dev/null
  rm -rf "$work"
fi
# Memcheck slows kernels many times over: two voxel types (plain, colour) of each typed suite, the
# tracked pipeline and the per-device engine tests, each within a time limit (a run cut short still
# reports what it found until then).
sanitizer=$(command -v compute-sanitizer || ls /usr/local/cuda/bin/compute-sanitizer 2>/dev/null || true)
if [ "${VOXFUSE_GPU_CHECK_MEMCHECK:-1}" != 0 ] && [ -n "$sanitizer" ]; then
  # No leak check: the test programs exit without destroying their CUDA context, which the leak
  # report needs to be meaningful.
  memcheck=("$sanitizer" --tool memcheck --error-exitcode 3)
  step memcheck_cuda_tests 150 "${memcheck[@]}" "$bundle/bin/voxfuse_cuda_tests" --gtest_brief=1 \
    --gtest_filter='*/0.*:*/2.*:Indexes/*:EngineCudaCapacity*:CudaDevice*'
  step memcheck_engine_tests 120 "${memcheck[@]}" "$bundle/bin/voxfuse_core_tests" --gtest_brief=1 --gtest_filter='*cuda*'
fi

python3 - "$out" <<'PY'
import json, os, sys, xml.etree.ElementTree as ET
out = sys.argv[1]
print("\n==== VoxFuse GPU check summary ====")
status = dict(line.split() for line in open(os.path.join(out, "status.txt")) if line.strip())
for name in ("cuda_tests", "engine_cuda_tests"):
    path = os.path.join(out, name + ".xml")
    if not os.path.exists(path):
        print(f"{name}: no result (exit {status.get(name)})"); continue
    root = ET.parse(path).getroot()
    tests, failures, errors = int(root.get("tests", 0)), int(root.get("failures", 0)), int(root.get("errors", 0))
    skipped = sum(1 for c in root.iter("testcase") if c.find("skipped") is not None)
    print(f"{name}: {tests} tests, {failures + errors} failed, {skipped} skipped (exit {status.get(name)})")
    for c in root.iter("testcase"):
        if c.find("failure") is not None:
            print("  FAILED", c.get("classname"), c.get("name"))
stages = ("depth", "track", "allocate", "integrate", "raycast", "total")
print(f"\n{'run':<20}" + "".join(f"{s:>10}" for s in stages) + f"{'a+i+r':>10}{'ATE mm':>9}")
for name in ("bench_cuda_hash", "bench_cuda_dense", "bench_cuda_tracked", "bench_cpu_hash", "teddy_cuda", "teddy_cpu"):
    path = os.path.join(out, name + ".json")
    if not os.path.exists(path):
        print(f"{name:<20}no result (exit {status.get(name)})"); continue
    j = json.load(open(path))
    st = j.get("stages", {})
    med = {s: st.get(s, {}).get("median_ms") for s in stages}
    air = sum(med[s] for s in ("allocate", "integrate", "raycast") if med[s] is not None)
    ate = j.get("ate_rmse_m")
    row = "".join(f"{med[s]:>10.3f}" if med[s] is not None else f"{'-':>10}" for s in stages)
    print(f"{name:<20}{row}{air:>10.3f}{(1000 * ate if ate is not None else float('nan')):>9.2f}")
    if "engine_fps_with_render" in j:
        render = st.get("render", {}).get("median_ms")
        print(f"{'':<20}{j['engine_fps']:.0f} frames/s; with a render per frame (shaded, brought to the host: {render:.3f} ms) "
              f"{j['engine_fps_with_render']:.0f} frames/s")
    if name == "bench_cuda_hash":
        print(f"{'':<20}gpu: {j.get('gpu', '?')}; {j.get('frames')} frames, median ms per stage; blocks {j.get('blocks_allocated')}, "
              f"allocation failures {j.get('allocation_failures')}")
    m, c = j.get("meshing"), j.get("point_cloud")
    if m:
        gpu_peak = f", GPU peak +{m['gpu_peak_extra_mb']:.1f} MB" if "gpu_peak_extra_mb" in m else ""
        print(f"{'':<20}mesh {m['median_ms']:.2f} ms ({m['triangles']} triangles, {m['vertices']} vertices{gpu_peak})"
              + (f"; cloud {c['extract_median_ms']:.2f} ms ({c['points']} points)" if c else ""))
for name in ("memcheck_cuda_tests", "memcheck_engine_tests"):
    path = os.path.join(out, name + ".log")
    if not os.path.exists(path):
        continue
    lines = [l.rstrip() for l in open(path, errors="replace")]
    summary = [l.strip("= ") for l in lines if "ERROR SUMMARY" in l]
    exit_code = status.get(name)
    verdict = {"0": "clean", "3": "errors found", "124": "cut short by its time limit"}.get(exit_code, f"exit {exit_code}")
    print(f"\n{name} (compute-sanitizer): {verdict}; " + ("; ".join(summary) if summary else "no summary line"))
    failed = [l for l in lines if l.startswith("[  FAILED  ]")]
    for l in ([l for l in lines if l.startswith("========= Invalid") or l.startswith("========= Program hit")] + failed)[:8]:
        print("  " + l)
parity = os.path.join(out, "teddy_parity.log")
if os.path.exists(parity):
    print("\nteddy (200 depth frames, ren, 5 mm hash), cpu against cuda (device_parity.py):")
    for line in open(parity):
        print("  " + line.rstrip())
print("logs and JSON:", out)
PY
