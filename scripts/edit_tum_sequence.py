#!/usr/bin/env python3
"""Makes a TUM RGB-D folder that plays another one's frames edited: some left out, some in another
order, some with their depth replaced by zeros (a covered lens). No image is copied: the new lists
name the original files, and blank depth is one all-zero PNG. For trying loss and relocalisation
on recorded data, e.g. (frame numbers count the depth images on disk, from 0):

  # 40 frames cut out of the recording
  scripts/edit_tum_sequence.py ../shared/data/tum_fr3_teddy_200 /tmp/teddy_cut --frames 0-79,120-192 --calib calib/tum_fr3.txt
  # out on the even frames, back on the odd ones, 40 frames cut from the way back
  scripts/edit_tum_sequence.py ../shared/data/tum_fr3_teddy_200 /tmp/teddy_back --frames 0-120/2,119-101/2,19-1/2 --calib calib/tum_fr3.txt
  # a covered lens for 20 frames
  scripts/edit_tum_sequence.py ../shared/data/tum_fr3_teddy_200 /tmp/teddy_covered --blank 80-99 --calib calib/tum_fr3.txt
  # a long run: played to and fro three times (1140 frames with colour), newly timed at 30 Hz
  scripts/edit_tum_sequence.py ../shared/data/tum_fr3_teddy_200 /tmp/teddy_long --frames 0-192,191-1,0-192,191-1,0-192,191-1 --retime 30 --calib calib/tum_fr3.txt
  voxfuse_bench /tmp/teddy_cut

A frame played twice keeps its timestamp, and a source pairs each colour image with one depth image:
give such sequences new timestamps (--retime); the ground truth then goes with them (each played frame's
pose interpolated at its original time, under its new one).
"""

import argparse
import bisect
import os
import shutil
import struct
import sys
import zlib


def read_list(folder, name):
    """(timestamp, absolute path) of the listed images that are on disk, in list order."""
    entries = []
    with open(os.path.join(folder, name)) as f:
        for line in f:
            fields = line.split()
            if len(fields) < 2 or fields[0].startswith("#"):
                continue
            path = os.path.abspath(os.path.join(folder, fields[1]))
            if os.path.exists(path):
                entries.append((fields[0], path))
    return entries


def pair_color(depth, rgb, max_difference_s=0.02):
    """The colour image of each depth image (None: none), paired as TumSource pairs them: one to one,
    closest in time first, at most max_difference_s apart."""
    rgb_times = sorted((float(stamp), path) for stamp, path in rgb)
    times = [t for t, _ in rgb_times]
    candidates = []
    for d, (stamp, _) in enumerate(depth):
        t = float(stamp)
        r = bisect.bisect_left(times, t - max_difference_s)
        while r < len(times) and times[r] <= t + max_difference_s:
            candidates.append((abs(times[r] - t), d, r))
            r += 1
    candidates.sort(key=lambda c: c[0])  # stable: ties keep depth order, as TumSource's stable_sort
    rgb_for, used = [None] * len(depth), set()
    for _, d, r in candidates:
        if rgb_for[d] is None and r not in used:
            rgb_for[d] = rgb_times[r][1]
            used.add(r)
    return rgb_for


def parse_ranges(text, count):
    """'0-79,120-192' or '0-120/2,119-1/2' (inclusive ends, either direction) -> frame numbers."""
    frames = []
    for part in text.split(","):
        span, _, step = part.partition("/")
        first, _, last = span.partition("-")
        first, last, step = int(first), int(last or first), int(step or 1)
        if step < 1 or not (0 <= first < count and 0 <= last < count):
            sys.exit(f"edit_tum_sequence: bad range '{part}' (frames 0..{count - 1}, step >= 1)")
        frames += list(range(first, last + 1, step) if last >= first else range(first, last - 1, -step))
    return frames


def write_zero_png(path, width, height):
    """A 16-bit greyscale PNG of zeros: depth 0 is 'no measurement'."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    rows = b"".join(b"\x00" + bytes(2 * width) for _ in range(height))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 16, 0, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(rows)))
        f.write(chunk(b"IEND", b""))


def read_ground_truth(path):
    poses = []
    with open(path) as f:
        for line in f:
            fields = line.split()
            if fields and not fields[0].startswith("#") and len(fields) == 8:
                poses.append([float(v) for v in fields])
    poses.sort()
    return poses


def interpolate_pose(poses, t, max_gap_s=0.05):
    """tx ty tz qx qy qz qw at time t: linear in position, normalised linear in the quaternion (poses a
    few ms apart); None outside the poses or across a gap."""
    lo, hi = 0, len(poses)
    while lo < hi:
        mid = (lo + hi) // 2
        if poses[mid][0] < t:
            lo = mid + 1
        else:
            hi = mid
    if lo == 0 or lo == len(poses):
        return poses[lo][1:] if lo < len(poses) and abs(poses[lo][0] - t) < 1e-6 else None
    a, b = poses[lo - 1], poses[lo]
    if b[0] - a[0] > max_gap_s:
        return None
    w = (t - a[0]) / (b[0] - a[0])
    qb = b[4:8] if sum(x * y for x, y in zip(a[4:8], b[4:8])) >= 0 else [-x for x in b[4:8]]
    q = [(1 - w) * x + w * y for x, y in zip(a[4:8], qb)]
    n = sum(x * x for x in q) ** 0.5
    return [(1 - w) * x + w * y for x, y in zip(a[1:4], b[1:4])] + [x / n for x in q]


def write_retimed_ground_truth(source, out, stamps):
    """`stamps`: (new timestamp text, original time) per played frame."""
    poses = read_ground_truth(source)
    with open(out, "w") as f:
        f.write("# ground truth of the played frames at their new times, edited by edit_tum_sequence.py\n")
        for new, original in stamps:
            pose = interpolate_pose(poses, original)
            if pose is not None:
                f.write(new + " " + " ".join(f"{v:.6f}" for v in pose) + "\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("source", help="TUM RGB-D folder (rgb.txt, depth.txt, optional groundtruth.txt)")
    parser.add_argument("out", help="folder to write (created; its lists are replaced)")
    parser.add_argument("--frames", help="frames to play, in order (default: all)")
    parser.add_argument("--blank", help="frames whose depth is replaced by zeros")
    parser.add_argument("--calib", help="calibration file to put in OUT/calib.txt (default: the source's own, if any)")
    parser.add_argument("--size", default="640x480", help="depth image size for the blank PNG (default 640x480)")
    parser.add_argument("--retime", type=float, metavar="HZ",
                        help="new timestamps, HZ per second, for each played frame and its colour image (the ground truth moves with them)")
    args = parser.parse_args()
    if args.retime is not None and not args.retime > 0:
        sys.exit("edit_tum_sequence: --retime needs a rate above 0")

    depth = read_list(args.source, "depth.txt")
    frames = parse_ranges(args.frames, len(depth)) if args.frames else list(range(len(depth)))
    blank = set(parse_ranges(args.blank, len(depth))) if args.blank else set()
    os.makedirs(args.out, exist_ok=True)
    blank_png = os.path.abspath(os.path.join(args.out, "blank_depth.png"))
    if blank:
        width, height = (int(v) for v in args.size.lower().split("x"))
        write_zero_png(blank_png, width, height)
    rgb = read_list(args.source, "rgb.txt")
    # Played frame k's timestamp: its own, or k / HZ from the source's first.
    def stamp_of(k, i):
        return depth[i][0] if args.retime is None else f"{float(depth[0][0]) + k / args.retime:.6f}"
    with open(os.path.join(args.out, "depth.txt"), "w") as f:
        f.write("# depth maps, edited by edit_tum_sequence.py\n")
        for k, i in enumerate(frames):
            f.write(f"{stamp_of(k, i)} {blank_png if i in blank else depth[i][1]}\n")
    with open(os.path.join(args.out, "rgb.txt"), "w") as f:
        if args.retime is None:
            f.write("# colour images of the source\n")
            for stamp, path in rgb:
                f.write(f"{stamp} {path}\n")
        else:
            f.write("# the colour image of each played depth image, edited by edit_tum_sequence.py\n")
            rgb_for = pair_color(depth, rgb)
            for k, i in enumerate(frames):
                if rgb_for[i] is not None:  # else the source drops this frame, as it dropped the original
                    f.write(f"{stamp_of(k, i)} {rgb_for[i]}\n")
    gt = os.path.abspath(os.path.join(args.source, "groundtruth.txt"))
    link = os.path.join(args.out, "groundtruth.txt")
    if args.retime is not None:
        if os.path.lexists(link):
            os.remove(link)  # an earlier edit's: its times no longer match
        if os.path.exists(gt):
            write_retimed_ground_truth(gt, link, [(stamp_of(k, i), float(depth[i][0])) for k, i in enumerate(frames)])
    elif os.path.exists(gt) and not os.path.lexists(link):
        os.symlink(gt, link)
    calib = args.calib or os.path.join(args.source, "calib.txt")
    if os.path.exists(calib):
        shutil.copyfile(calib, os.path.join(args.out, "calib.txt"))
    print(f"edit_tum_sequence: {len(frames)} frames ({len(blank & set(frames))} blank) -> {args.out}")


if __name__ == "__main__":
    main()
