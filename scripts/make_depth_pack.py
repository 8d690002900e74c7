#!/usr/bin/env python3
"""Packs the first frames of a TUM RGB-D folder's depth into a VoxFuse depth pack
(apps/common/DepthPackSource.h): a recording that voxfuse_bench reads without image codecs, for
machines that have only the core library (the GPU bundle of scripts/gpu_bundle.sh).

    scripts/make_depth_pack.py TUM_FOLDER OUT_FOLDER --frames 60 --calib calib/tum_fr3.txt

Needs numpy and Pillow (pip install numpy pillow). Writes calib.txt, depth.bin.gz and, when the
folder has one, groundtruth.txt (the poses within the frames' time span, TUM format).
write_depth_pack() is the format's one writer (tests/cli/bench_depth_pack.py uses it too)."""
import argparse
import gzip
import os
import shutil
import struct
import sys


def write_depth_pack(folder, calib_text, width, height, frames, groundtruth_lines=(), cut_at_byte=None):
    """Writes a pack into `folder` (replaced whole; written beside it first). `frames` yields
    (timestamp_s, depth) with depth width * height little-endian uint16 bytes. `cut_at_byte` ends the
    uncompressed stream there: a damaged pack, for tests."""
    frames = list(frames)
    tmp = folder + ".partial"
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(tmp)
    with open(os.path.join(tmp, "calib.txt"), "w") as f:
        f.write(calib_text)
    written = 0

    with gzip.open(os.path.join(tmp, "depth.bin.gz"), "wb", compresslevel=6) as out:
        def put(chunk):
            nonlocal written
            room = len(chunk) if cut_at_byte is None else max(0, min(len(chunk), cut_at_byte - written))
            out.write(chunk[:room])
            written += room

        put(b"VFDEPTH1" + struct.pack("<III", width, height, len(frames)))
        for stamp, depth in frames:
            if len(depth) != 2 * width * height:
                raise ValueError(f"a frame of {len(depth)} bytes, expected {2 * width * height}")
            put(struct.pack("<d", stamp))
            put(depth)
    if groundtruth_lines:
        with open(os.path.join(tmp, "groundtruth.txt"), "w") as g:
            g.writelines(groundtruth_lines)
    shutil.rmtree(folder, ignore_errors=True)
    os.replace(tmp, folder)


def depth_list(folder):
    """(timestamp, path) of every depth image in depth.txt, in order."""
    path = os.path.join(folder, "depth.txt")
    if not os.path.exists(path):
        sys.exit(f"make_depth_pack.py: {path}: not found (is {folder} a TUM folder?)")
    frames = []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            if line.startswith("#") or not line.strip():
                continue
            parts = line.split()
            if len(parts) != 2:
                sys.exit(f"make_depth_pack.py: {path}:{number}: expected 'timestamp file'")
            frames.append((float(parts[0]), os.path.join(folder, parts[1])))
    # A subset of a sequence (as ../shared/data holds) keeps the full list: the images it lacks go.
    present = [f for f in frames if os.path.exists(f[1])]
    if len(present) < len(frames):
        print(f"make_depth_pack.py: {len(frames) - len(present)} of the {len(frames)} listed depth images are not in {folder}; left out")
    return present


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("tum_folder")
    ap.add_argument("out_folder")
    ap.add_argument("--frames", type=int, default=60, help="the first N depth images (default 60)")
    ap.add_argument("--calib", required=True, help="the folder's calibration (InfiniTAM format, e.g. calib/tum_fr3.txt)")
    args = ap.parse_args()
    if args.frames < 1:
        sys.exit("make_depth_pack.py: --frames must be at least 1")

    try:
        import numpy as np
        from PIL import Image
    except ImportError as e:
        sys.exit(f"make_depth_pack.py: {e.name} is missing (pip install numpy pillow)")
    frames = depth_list(args.tum_folder)[: args.frames]
    if not frames:
        sys.exit(f"make_depth_pack.py: {args.tum_folder}: no depth images listed")
    size = None
    depths = []
    for index, (stamp, path) in enumerate(frames):
        depth = np.asarray(Image.open(path))
        if depth.ndim != 2 or depth.dtype.kind not in "iu" or depth.max(initial=0) > 65535:
            sys.exit(f"make_depth_pack.py: {path}: frame {index}: not a 16-bit depth image ({depth.dtype}, shape {depth.shape})")
        if size is None:
            size = depth.shape
        elif depth.shape != size:
            sys.exit(f"make_depth_pack.py: {path}: frame {index}: {depth.shape[1]}x{depth.shape[0]}, the first was {size[1]}x{size[0]}")
        depths.append((stamp, depth.astype("<u2").tobytes()))

    groundtruth = []
    gt = os.path.join(args.tum_folder, "groundtruth.txt")
    if os.path.exists(gt):
        first, last = frames[0][0] - 0.1, frames[-1][0] + 0.1
        groundtruth.append(f"# from {gt}, the poses of {len(frames)} depth frames\n")
        with open(gt) as f:
            groundtruth += [line for line in f if line.strip() and not line.startswith("#") and first <= float(line.split()[0]) <= last]
    with open(args.calib) as f:
        calib_text = f.read()
    write_depth_pack(args.out_folder, calib_text, size[1], size[0], depths, groundtruth)
    mib = os.path.getsize(os.path.join(args.out_folder, "depth.bin.gz")) / 2**20
    print(f"make_depth_pack.py: {args.out_folder}: {len(frames)} frames of {size[1]}x{size[0]}, {mib:.1f} MiB")


if __name__ == "__main__":
    main()
