#!/usr/bin/env python3
"""The tables of a GPU check (scripts/gpu_check.sh), from what its steps left in OUT: per step its
result and time, the cuda tests (failed ones named), per-stage median milliseconds of every bench,
meshing, compute-sanitizer's findings and the CPU-GPU parity on teddy. Reads whatever is there: a
check cut short still gets the tables of the steps that finished. Standard library only.

    gpu_check_summary.py OUT BUNDLE"""
import json
import os
import sys
import xml.etree.ElementTree as ET

STAGES = ("depth", "track", "allocate", "integrate", "raycast", "total")


def read_status(out):
    steps = []
    path = os.path.join(out, "status.txt")
    if os.path.exists(path):
        for line in open(path):
            words = line.split()
            if len(words) >= 2:
                steps.append((words[0], words[1], words[2] if len(words) > 2 else "?"))
    return steps


def test_lines(out, name, result):
    path = os.path.join(out, name + ".xml")
    if not os.path.exists(path):
        return [f"{name}: no result ({result})"]
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        return [f"{name}: unreadable XML ({e})"]
    cases = list(root.iter("testcase"))
    skipped = sum(1 for c in cases if c.find("skipped") is not None)
    failed = [c for c in cases if c.find("failure") is not None or c.find("error") is not None]
    lines = [f"{name}: {len(cases)} tests, {len(failed)} failed, {skipped} skipped ({result})"]
    lines += [f"  FAILED {c.get('classname')}.{c.get('name')}" for c in failed[:20]]
    if len(failed) > 20:
        lines.append(f"  ... and {len(failed) - 20} more")
    return lines


def bench_lines(out, bundle):
    runs = [("teddy_cuda", os.path.join(out, "teddy_cuda.json")),
            ("teddy_cpu (reference)", os.path.join(bundle, "reference", "teddy_cpu.json")),
            ("bench_cuda_tracked", os.path.join(out, "bench_cuda_tracked.json")),
            ("bench_cuda_hash", os.path.join(out, "bench_cuda_hash.json")),
            ("bench_cuda_dense", os.path.join(out, "bench_cuda_dense.json"))]
    lines = ["", "median ms per stage (CUDA events on the GPU)",
             f"{'run':<24}" + "".join(f"{s:>10}" for s in STAGES) + f"{'frames/s':>10}{'ATE mm':>9}"]
    for name, path in runs:
        if not os.path.exists(path):
            lines.append(f"{name:<24}no result")
            continue
        try:
            j = json.load(open(path))
        except (OSError, ValueError) as e:
            lines.append(f"{name:<24}unreadable ({e})")
            continue
        st = j.get("stages", {})
        med = [st.get(s, {}).get("median_ms") for s in STAGES]
        row = "".join(f"{m:>10.3f}" if isinstance(m, (int, float)) else f"{'-':>10}" for m in med)
        fps = j.get("engine_fps")
        ate = j.get("ate_rmse_m")
        lines.append(f"{name:<24}{row}" + (f"{fps:>10.0f}" if isinstance(fps, (int, float)) else f"{'-':>10}")
                     + (f"{1000 * ate:>9.2f}" if isinstance(ate, (int, float)) else f"{'-':>9}"))
        extra = []
        if "gpu" in j:
            extra.append(f"gpu: {j['gpu']}")
        if "blocks_allocated" in j:
            extra.append(f"blocks {j['blocks_allocated']}, allocation failures {j.get('allocation_failures')}")
        m = j.get("meshing")
        if m:
            extra.append(f"mesh {m.get('median_ms', float('nan')):.2f} ms ({m.get('triangles')} triangles)")
        if "engine_fps_with_render" in j:
            extra.append(f"{j['engine_fps_with_render']:.0f} frames/s with a render per frame")
        if extra:
            lines.append(f"{'':<24}" + "; ".join(extra))
    return lines


def memcheck_lines(out, status):
    lines = []
    for name in ("memcheck_cuda_tests", "memcheck_engine_tests"):
        path = os.path.join(out, name + ".log")
        if not os.path.exists(path):
            continue
        text = [l.rstrip() for l in open(path, errors="replace")]
        found = [l.strip("= ") for l in text if "ERROR SUMMARY" in l]
        lines.append(f"{name} (compute-sanitizer memcheck): {status.get(name, '?')}; " + ("; ".join(found) if found else "no summary line"))
        hits = [l for l in text if l.startswith("========= Invalid") or l.startswith("========= Program hit") or l.startswith("[  FAILED  ]")]
        lines += ["  " + l for l in hits[:8]]
    return ([""] + lines) if lines else []


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    out, bundle = sys.argv[1], sys.argv[2]
    steps = read_status(out)
    status = {name: result for name, result, _ in steps}
    lines = ["", "==== VoxFuse GPU check summary ====", f"{'step':<24}{'result':<28}{'seconds':>8}"]
    lines += [f"{name:<24}{result:<28}{secs:>8}" for name, result, secs in steps]
    lines.append("")
    for name in ("cuda_tests", "engine_cuda_tests"):
        if name in status:
            lines += test_lines(out, name, status[name])
    lines += bench_lines(out, bundle)
    lines += memcheck_lines(out, status)
    parity = os.path.join(out, "teddy_parity.log")
    if os.path.exists(parity):
        lines += ["", "teddy (200 depth frames, ren, 5 mm hash), CPU reference against cuda (device_parity.py):"]
        lines += ["  " + l.rstrip() for l in open(parity, errors="replace")]
    lines.append(f"logs and JSON: {out}")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
