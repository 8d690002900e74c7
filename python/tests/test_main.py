"""python -m voxfuse: the Python entry point's outputs, refusals and exit statuses."""

import json
import subprocess
import sys

import numpy as np

from conftest import SYNTHETIC_ROOM


def voxfuse_py(*args):
    return subprocess.run([sys.executable, "-m", "voxfuse", *map(str, args)], capture_output=True, text=True,
                          timeout=300)


def test_a_run_writes_trajectory_summary_and_mesh(tmp_path):
    # A list of ints whose default is empty takes ints (the table says the type, not the default).
    run = voxfuse_py(SYNTHETIC_ROOM, "--out", tmp_path, "--frames", 5, "--mesh", "--set", "voxel_size=0.01",
                     "--set", "tracker_iterations=10,10,10")
    assert run.returncode == 0, run.stderr
    assert np.loadtxt(tmp_path / "trajectory.txt").shape == (5, 8)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["frames"] == 5 and summary["frames_fused"] == 5
    assert summary["voxel_size_m"] == 0.01 or abs(summary["voxel_size_m"] - 0.01) < 1e-6
    assert summary["trajectory_error"]["ate_rmse_m"] < 0.005  # the room's exact ground truth
    assert (tmp_path / "mesh.ply").stat().st_size > 1000


def test_an_earlier_runs_outputs_are_kept_unless_overwrite(tmp_path):
    assert voxfuse_py(SYNTHETIC_ROOM, "--out", tmp_path, "--frames", 2).returncode == 0
    before = (tmp_path / "trajectory.txt").read_bytes()
    again = voxfuse_py(SYNTHETIC_ROOM, "--out", tmp_path, "--frames", 3)
    assert again.returncode == 2 and "--overwrite" in again.stderr
    assert (tmp_path / "trajectory.txt").read_bytes() == before
    assert voxfuse_py(SYNTHETIC_ROOM, "--out", tmp_path, "--frames", 3, "--overwrite").returncode == 0
    assert np.loadtxt(tmp_path / "trajectory.txt").shape == (3, 8)


def test_bad_settings_and_sources_are_refused_with_the_reason(tmp_path):
    unknown = voxfuse_py(SYNTHETIC_ROOM, "--out", tmp_path, "--set", "voxel_sise=0.01")
    assert unknown.returncode == 2 and "unknown setting 'voxel_sise'" in unknown.stderr
    wrong_type = voxfuse_py(SYNTHETIC_ROOM, "--out", tmp_path, "--set", "voxel_size=fine")
    assert wrong_type.returncode == 2 and "takes a float" in wrong_type.stderr
    out_of_range = voxfuse_py(SYNTHETIC_ROOM, "--out", tmp_path, "--set", "voxel_size=-1")
    assert out_of_range.returncode == 2 and "setting 'voxel_size': -1 is not in (0, 1]" in out_of_range.stderr
    missing = voxfuse_py(tmp_path / "nothing_here", "--out", tmp_path)
    assert missing.returncode == 2 and "no such file or folder" in missing.stderr
    rerun_target = voxfuse_py(SYNTHETIC_ROOM, "--out", tmp_path, "--frames", 1, "--rerun", "run.txt")
    assert rerun_target.returncode == 2
    assert "ending .rrd" in rerun_target.stderr or "pip install rerun-sdk" in rerun_target.stderr
    assert not (tmp_path / "trajectory.txt").exists()  # nothing half-written by a refused run
