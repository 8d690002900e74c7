#!/usr/bin/env python3
"""What an ATE is made of: a TUM trajectory against TUM ground truth, with the ground truth
interpolated at the frame times (not paired by nearest timestamp, as the ATE itself is), then

  - the clock offset that fits best (searched in 1 ms steps),
  - at that offset, fits with more freedom than a rigid alignment: a lever arm between the
    ground truth's body and the camera (constant in the body frame), and a scale,
  - how much of the error is slow (a moving average over --window frames) and how much jitter,
  - the error along the camera's own axes (x right, y down, z along the optical axis).

A fit with more freedom that takes much of the error away says where it comes from (a lever arm:
the ground truth's hand-eye calibration; a scale: the depth's); one that does not rules that out.

  scripts/ate_breakdown.py OUT/trajectory.txt ../shared/data/tum_fr3_teddy_200/groundtruth.txt

Needs numpy only.
"""

import argparse
import sys

import numpy as np


def read_tum(path):
    rows = []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            values = line.split()
            if len(values) != 8:
                sys.exit(f"{path}:{number}: expected 'timestamp tx ty tz qx qy qz qw', got {len(values)} values")
            rows.append([float(v) for v in values])
    if len(rows) < 3:
        sys.exit(f"{path}: fewer than 3 poses")
    a = np.array(rows)
    return a[np.argsort(a[:, 0])]


def rotations(q):  # (N, 4) as x y z w -> (N, 3, 3)
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    x, y, z, w = q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1)], 1)


def truth_at(gt, t):
    """Ground-truth positions interpolated at times t, rotations of the nearer sample; a mask of the
    times inside the ground truth's span with samples at most 50 ms apart around them."""
    i = np.clip(np.searchsorted(gt[:, 0], t), 1, len(gt) - 1)
    t0, t1 = gt[i - 1, 0], gt[i, 0]
    inside = (t >= t0) & (t <= t1) & (t1 - t0 <= 0.05)
    a = np.clip((t - t0) / np.maximum(t1 - t0, 1e-9), 0.0, 1.0)[:, None]
    p = gt[i - 1, 1:4] * (1 - a) + gt[i, 1:4] * a
    R = rotations(np.where(a < 0.5, gt[i - 1, 4:8], gt[i, 4:8]))
    return p, R, inside


def align(src, dst, with_scale):
    """s, R, t with dst ~ s R src + t (Umeyama)."""
    ms, md = src.mean(0), dst.mean(0)
    U, S, Vt = np.linalg.svd((dst - md).T @ (src - ms))
    D = np.eye(3)
    D[2, 2] = np.sign(np.linalg.det(U @ Vt))
    R = U @ D @ Vt
    s = (S * np.diag(D)).sum() / ((src - ms) ** 2).sum() if with_scale else 1.0
    return s, R, md - s * R @ ms


def fit(est, gt, offset, lever=False, scale=False):
    """RMS error (m), the error vectors, the lever arm (m, body frame) and the scale at a time offset
    (added to the frame times)."""
    p, R_gt, inside = truth_at(gt, est[:, 0] + offset)
    P, p, R_gt = est[inside, 1:4], p[inside], R_gt[inside]
    arm = np.zeros(3)
    for _ in range(50 if lever else 1):  # alternate: alignment for a fixed arm, arm for a fixed alignment
        target = p + R_gt @ arm
        s, R, t = align(P, target, scale)
        moved = s * P @ R.T + t
        if lever:
            arm = np.linalg.lstsq(R_gt.reshape(-1, 3), (moved - p).reshape(-1), rcond=None)[0]
    e = moved - (p + R_gt @ arm)
    return np.sqrt((e ** 2).sum(1).mean()), e, R_gt, arm, s


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("trajectory", help="estimated poses (TUM format, camera to world)")
    ap.add_argument("groundtruth", help="ground truth (TUM format)")
    ap.add_argument("--max-offset-ms", type=float, default=100.0, help="offsets searched: within this (default 100)")
    ap.add_argument("--window", type=int, default=9, help="frames of the moving average that takes the slow part (default 9)")
    args = ap.parse_args()
    est, gt = read_tum(args.trajectory), read_tum(args.groundtruth)
    mm = lambda m: f"{1000.0 * m:.2f} mm"

    zero = fit(est, gt, 0.0)[0]
    offsets = np.arange(-args.max_offset_ms, args.max_offset_ms + 0.5, 1.0) / 1000.0
    errors = [fit(est, gt, o)[0] for o in offsets]
    best = float(offsets[int(np.argmin(errors))])
    rms, e, R_gt, _, _ = fit(est, gt, best)
    print(f"ATE, ground truth interpolated:   {mm(zero)}")
    print(f"at the best clock offset:         {mm(rms)} ({1000.0 * best:+.0f} ms added to the frame times)")
    for lever, scale, what in ((True, False, "and a lever arm"), (False, True, "and a scale"), (True, True, "and both")):
        r, _, _, arm, s = fit(est, gt, best, lever, scale)
        print(f"  {what + ':':<31} {mm(r)} (arm {np.round(1000.0 * arm, 1)} mm, scale {s:.4f})")
    k = max(1, args.window)
    pad = np.pad(e, ((k // 2, k - 1 - k // 2), (0, 0)), mode="edge")
    slow = np.stack([np.convolve(pad[:, a], np.ones(k) / k, mode="valid") for a in range(3)], 1)
    print(f"slow part ({k}-frame mean):         {mm(np.sqrt((slow ** 2).sum(1).mean()))}, "
          f"jitter {mm(np.sqrt(((e - slow) ** 2).sum(1).mean()))}")
    in_camera = np.einsum("nji,nj->ni", R_gt, e)  # R^T e: the error in the ground truth's camera frame
    x, y, z = np.sqrt((in_camera ** 2).mean(0))
    print(f"along the camera's x, y, z:       {mm(x)}, {mm(y)}, {mm(z)}")
    thirds = [np.sqrt((c ** 2).sum(1).mean()) for c in np.array_split(e, 3)]
    print("by thirds of the run:             " + ", ".join(mm(t) for t in thirds))


if __name__ == "__main__":
    main()
