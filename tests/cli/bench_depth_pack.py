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
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import make_depth_pack  # noqa: E402  (the format's one writer)

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


def write_pack(folder, magic_ok=True, cut_at_byte=None):
    """The corner seen FRAMES times from the origin; returns the bytes of one frame's depth."""
    calib = "".join(f"{W} {H}\n{FX} {FY}\n{CX} {CY}\n\n" for _ in range(2)) + "1 0 0 0\n0 1 0 0\n0 0 1 0\n\naffine 0.001 0\n"
    depth = corner_depth_mm().tobytes()
    stamps = [100.0 + k / 30.0 for k in range(FRAMES)]
    make_depth_pack.write_depth_pack(folder, calib, W, H, [(t, depth) for t in stamps], [f"{t:.6f} 0 0 0 0 0 0 1\n" for t in stamps],
                                     cut_at_byte=cut_at_byte)
    if not magic_ok:  # the same pack under another format's name
        path = os.path.join(folder, "depth.bin.gz")
        with gzip.open(path) as f:
            data = f.read()
        with gzip.open(path, "wb") as f:
            f.write(b"VFDEPTH9" + data[8:])
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
    write_pack(cut, cut_at_byte=20 + 7 * (8 + frame_bytes) + 8 + 1000)
    rc, out = run([args.bench, cut, "--warmup", "1", "--json", os.path.join(args.work, "cut.json")])
    check(rc == 0 and "depth.bin.gz: frame 7: truncated" in out, f"a truncated pack is reported with file, frame and reason (exit {rc})")
    cut_report = json.load(open(os.path.join(args.work, "cut.json"))) if rc == 0 else {}
    check(cut_report.get("frames") == 7, f"the frames before the cut ran (got {cut_report.get('frames')})")
    if "frame 7: truncated" not in out:
        print(out)
    bad = os.path.join(args.work, "bad")
    write_pack(bad, magic_ok=False)
    rc, out = run([args.bench, bad, "--json", os.path.join(args.work, "bad.json")])
    check(rc != 0 and "not a VoxFuse depth pack" in out, f"a wrong header is refused (exit {rc})")

    print(f"bench_depth_pack: {len(failures)} of the checks failed" if failures else "bench_depth_pack: all checks passed")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
