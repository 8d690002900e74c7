#!/usr/bin/env python3
"""voxfuse_bench on a depth pack (apps/common/DepthPackSource.h), the recording format the GPU bundle
carries: a pack of a static camera in a room corner (three planes, depth computed exactly, ground
truth the identity) is read frame by frame, tracked to the ground truth, and written out as a
trajectory and a mesh that device_parity.py accepts against itself; a truncated pack and one with a
wrong header end with an error naming the file, the frame and the reason.

    bench_depth_pack.py --bench BUILD/apps/voxfuse_bench --parity scripts/device_parity.py --work DIR"""
import argparse
import gzip
import json
import os
import shutil
import struct
import subprocess
import sys

import numpy as np

W, H, FRAMES = 320, 240, 12
FX = FY = 262.5
CX, CY = 159.5, 119.5


def corner_depth_mm():
    """Depth (mm) of the planes x = -0.6 m (a wall), y = 0.5 m (the floor, y down) and z = 2 m (the
    back wall), seen from the origin looking along +z."""
    u, v = np.meshgrid(np.arange(W, dtype=np.float64), np.arange(H, dtype=np.float64))
    dx, dy = (u - CX) / FX, (v - CY) / FY
    z = np.full((H, W), 2.0)
    with np.errstate(divide="ignore"):
        z = np.where(dx < 0, np.minimum(z, -0.6 / dx), z)
        z = np.where(dy > 0, np.minimum(z, 0.5 / dy), z)
    return np.round(z * 1000.0).astype("<u2")


def write_pack(folder, frames=FRAMES, magic=b"VFDEPTH1", truncate_at=None):
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    with open(os.path.join(folder, "calib.txt"), "w") as f:
        for _ in range(2):
            f.write(f"{W} {H}\n{FX} {FY}\n{CX} {CY}\n\n")
        f.write("1 0 0 0\n0 1 0 0\n0 0 1 0\n\naffine 0.001 0\n")
    depth = corner_depth_mm().tobytes()
    data = magic + struct.pack("<III", W, H, frames)
    for k in range(frames):
        data += struct.pack("<d", 100.0 + k / 30.0) + depth
    if truncate_at is not None:
        data = data[:truncate_at]
    with gzip.open(os.path.join(folder, "depth.bin.gz"), "wb") as f:
        f.write(data)
    with open(os.path.join(folder, "groundtruth.txt"), "w") as f:
        for k in range(frames):
            f.write(f"{100.0 + k / 30.0:.6f} 0 0 0 0 0 0 1\n")
    return len(depth)


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    return p.returncode, p.stdout + p.stderr


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bench", required=True)
    ap.add_argument("--parity", required=True)
    ap.add_argument("--work", required=True)
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    failures = []

    def check(ok, what):
        print(("ok   " if ok else "FAIL ") + what)
        if not ok:
            failures.append(what)

    pack = os.path.join(args.work, "corner")
    frame_bytes = write_pack(pack)
    prefix = os.path.join(args.work, "run")
    rc, out = run([args.bench, pack, "--voxel-size", "0.01", "--mu", "0.04", "--warmup", "1", "--json", prefix + ".json",
                   "--trajectory", prefix + "_trajectory.txt", "--mesh", "--repeats", "1", "--mesh-out", prefix + "_mesh.ply"])
    check(rc == 0, f"the tracked run on the pack succeeds (exit {rc})")
    if rc != 0:
        print(out)
    check(f"depth pack {pack} ({FRAMES} frames of {W}x{H}, ground truth)" in out, "the source describes itself")
    report = json.load(open(prefix + ".json")) if os.path.exists(prefix + ".json") else {}
    check(report.get("frames") == FRAMES, f"all {FRAMES} frames were read (got {report.get('frames')})")
    check(report.get("tracking_failed_frames") == 0, "no frame failed tracking")
    check(report.get("ate_rmse_m", 1.0) < 0.002, f"the static camera stays put: ATE {report.get('ate_rmse_m')} m < 2 mm")
    lines = [l for l in open(prefix + "_trajectory.txt") if l.strip() and not l.startswith("#")] if os.path.exists(prefix + "_trajectory.txt") else []
    check(len(lines) == FRAMES, f"the trajectory has a pose per frame ({len(lines)})")
    check(report.get("meshing", {}).get("triangles", 0) > 1000, "the map has a mesh")
    rc, out = run([sys.executable, args.parity, prefix, prefix])
    check(rc == 0 and "device parity: PASS" in out, "device_parity.py accepts a run against itself")
    if rc != 0:
        print(out)

    # A pack cut in frame 7's depth: as for any unreadable frame, the run reports it (file, frame,
    # reason) and goes on; a stream cannot skip to the next frame, so the first seven are all there is.
    cut = os.path.join(args.work, "cut")
    write_pack(cut, truncate_at=20 + 7 * (8 + frame_bytes) + 8 + 1000)
    rc, out = run([args.bench, cut, "--warmup", "1", "--json", os.path.join(args.work, "cut.json")])
    check(rc == 0 and "depth.bin.gz: frame 7: truncated" in out, f"a truncated pack is reported with file, frame and reason (exit {rc})")
    cut_report = json.load(open(os.path.join(args.work, "cut.json"))) if rc == 0 else {}
    check(cut_report.get("frames") == 7, f"the frames before the cut ran (got {cut_report.get('frames')})")
    if "frame 7: truncated" not in out:
        print(out)
    bad = os.path.join(args.work, "bad")
    write_pack(bad, magic=b"VFDEPTH9")
    rc, out = run([args.bench, bad, "--json", os.path.join(args.work, "bad.json")])
    check(rc != 0 and "not a VoxFuse depth pack" in out, f"a wrong header is refused (exit {rc})")

    print(f"bench_depth_pack: {len(failures)} of the checks failed" if failures else "bench_depth_pack: all checks passed")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
