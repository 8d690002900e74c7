#!/usr/bin/env python3
"""VoxFuse's default pipeline against Open3D's tensor SLAM on the same TUM frames, run alternately.

Open3D is never a dependency: install it in a virtual environment of its own and name its Python,

  python3 -m venv /tmp/o3d && /tmp/o3d/bin/pip install open3d
  scripts/compare_open3d.py --open3d-python /tmp/o3d/bin/python --rounds 2 [SEQ]

SEQ is a TUM RGB-D folder (default ../shared/data/tum_fr3_teddy_200). Each round runs `voxfuse SEQ`
(the CLI's defaults, no renders), then Open3D on the frames VoxFuse used (its trajectory's
timestamps: depth images, each with its colour image) with `open3d.t.pipelines.slam.Model` set up as
Open3D's dense SLAM example is (5 mm voxels, 16^3 blocks, depth scale 5000, 3 m depth, frame-to-model
tracking, integration and raycast every frame; `--block-count`, default 10000). A frame's time is
that of the engine's work (tracking, integration, raycast), image decoding left out on both sides;
the table shows each side's median over the frames, per round, the ratio, ATE RMSE against the
ground truth (VoxFuse's evaluation for both) and peak RSS.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_SEQ = os.path.join(REPO, "..", "shared", "data", "tum_fr3_teddy_200")

# Run by the Open3D interpreter: argv = frames.json, trajectory out, timings out.
OPEN3D_RUN = r"""
import json, resource, sys, time
import numpy as np
import open3d as o3d
import open3d.core as o3c

job = json.load(open(sys.argv[1]))
device = o3c.Device("CPU:0")
fx, fy, cx, cy = job["intrinsics"]
K = o3c.Tensor([[fx, 0, cx], [0, fy, cy], [0, 0, 1]], o3c.Dtype.Float64)
T = o3c.Tensor(np.identity(4))
model = o3d.t.pipelines.slam.Model(job["voxel_size"], 16, job["block_count"], T, device)
depth0 = o3d.t.io.read_image(job["frames"][0][1])
frame = o3d.t.pipelines.slam.Frame(depth0.rows, depth0.columns, K, device)
raycast = o3d.t.pipelines.slam.Frame(depth0.rows, depth0.columns, K, device)
poses, ms = [], []
for i, (stamp, depth_path, color_path) in enumerate(job["frames"]):
    depth = o3d.t.io.read_image(depth_path).to(device)
    color = o3d.t.io.read_image(color_path).to(device)
    start = time.perf_counter()
    frame.set_data_from_image("depth", depth)
    frame.set_data_from_image("color", color)
    if i > 0:
        result = model.track_frame_to_model(frame, raycast, job["depth_scale"], job["depth_max"], 0.07)
        T = T @ result.transformation
    model.update_frame_pose(i, T)
    model.integrate(frame, job["depth_scale"], job["depth_max"], 8.0)
    model.synthesize_model_frame(raycast, job["depth_scale"], 0.1, job["depth_max"], 8.0, False)
    ms.append(1000.0 * (time.perf_counter() - start))
    poses.append([stamp] + T.cpu().numpy().reshape(-1).tolist())
json.dump({"poses": poses, "ms": ms,
           "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
           "version": o3d.__version__}, open(sys.argv[2], "w"))
"""


def read_list(path):
    """A TUM list file (timestamp, file name) as [(timestamp, absolute path)]."""
    rows = []
    with open(path) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                stamp, name = line.split()[:2]
                rows.append((float(stamp), os.path.join(os.path.dirname(path), name)))
    return rows


def nearest(rows, stamp):
    return min(rows, key=lambda r: abs(r[0] - stamp))


def run_voxfuse(voxfuse, seq, out):
    subprocess.run([voxfuse, seq, "--out", out, "--render-every", "0", "--overwrite"], check=True,
                   capture_output=True, text=True)
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


def frames_of(trajectory, seq):
    """The (timestamp, depth, colour) of every frame VoxFuse's trajectory has a pose for."""
    depth, color = read_list(os.path.join(seq, "depth.txt")), read_list(os.path.join(seq, "rgb.txt"))
    frames = []
    with open(trajectory) as f:
        for line in f:
            if line.strip() and not line.startswith("#"):
                stamp = float(line.split()[0])
                d = nearest(depth, stamp)
                frames.append((d[0], d[1], nearest(color, d[0])[1]))
    return frames


def ate_of(poses, seq, python_path):
    """ATE RMSE (m) of Open3D's poses against the folder's ground truth, by VoxFuse's evaluation."""
    code = (
        "import json, sys, numpy as np, voxfuse\n"
        "rows = np.array(json.load(open(sys.argv[1])))\n"
        "gt_timestamps, gt_poses = voxfuse.read_tum_trajectory(sys.argv[2])\n"
        "e = voxfuse.evaluate_trajectory(rows[:, 0], rows[:, 1:].reshape(-1, 4, 4), gt_timestamps, gt_poses)\n"
        "print(e['ate_rmse_m'])\n"
    )
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump(poses, f)
    try:
        env = dict(os.environ, PYTHONPATH=python_path)
        out = subprocess.run([sys.executable, "-c", code, f.name, os.path.join(seq, "groundtruth.txt")], env=env,
                             check=True, capture_output=True, text=True).stdout
        return float(out.split()[-1])
    finally:
        os.unlink(f.name)


def median(values):
    values = sorted(values)
    n = len(values)
    return values[n // 2] if n % 2 else 0.5 * (values[n // 2 - 1] + values[n // 2])


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("seq", nargs="?", default=DEFAULT_SEQ)
    p.add_argument("--open3d-python", required=True, help="a Python that imports open3d")
    p.add_argument("--build", default=os.path.join(REPO, "build"))
    p.add_argument("--rounds", type=int, default=2)
    p.add_argument("--block-count", type=int, default=10000)
    p.add_argument("--intrinsics", type=float, nargs=4, default=[535.4, 539.2, 320.1, 247.6],
                   metavar=("FX", "FY", "CX", "CY"), help="default: TUM fr3")
    args = p.parse_args()
    voxfuse = os.path.join(args.build, "apps", "voxfuse")
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for round_ in range(args.rounds):
            ours = run_voxfuse(voxfuse, args.seq, os.path.join(work, "voxfuse"))
            frames = frames_of(os.path.join(work, "voxfuse", "trajectory.txt"), args.seq)
            job = {"frames": frames, "intrinsics": args.intrinsics, "voxel_size": 0.005, "block_count": args.block_count,
                   "depth_scale": 5000.0, "depth_max": 3.0}
            job_path, result_path = os.path.join(work, "job.json"), os.path.join(work, "open3d.json")
            with open(job_path, "w") as f:
                json.dump(job, f)
            subprocess.run([args.open3d_python, "-c", OPEN3D_RUN, job_path, result_path], check=True)
            with open(result_path) as f:
                theirs = json.load(f)
            theirs_ate = ate_of(theirs["poses"], args.seq, os.path.join(args.build, "python"))
            rows.append((round_ + 1, ours["median_ms"], median(theirs["ms"][1:]), ours["ate_rmse_m"], theirs_ate,
                         ours["peak_rss_mb"], theirs["peak_rss_mb"], theirs["version"]))
    print(f"{len(frames)} frames of {args.seq}; Open3D {rows[0][7]}")
    print("round  voxfuse ms  open3d ms  ratio  ATE voxfuse mm  ATE open3d mm  RSS voxfuse MB  RSS open3d MB")
    for r in rows:
        print(f"{r[0]:5d}  {r[1]:10.1f}  {r[2]:9.1f}  {r[1] / r[2]:5.2f}  {1000 * r[3]:13.2f}  {1000 * r[4]:13.2f}"
              f"  {r[5]:14.0f}  {r[6]:13.0f}")


if __name__ == "__main__":
    main()
