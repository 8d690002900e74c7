"""Rerun logging, headless: a short run saved to an .rrd file and read back entity by entity."""

import subprocess
import sys

import numpy as np
import pytest

import voxfuse

from conftest import SYNTHETIC_ROOM

FRAMES, MESH_EVERY = 6, 3


def test_without_rerun_sdk_the_error_says_how_to_install_it(monkeypatch, room_frames):
    monkeypatch.setitem(sys.modules, "rerun", None)
    source, frames = room_frames
    pipeline = voxfuse.Pipeline(source.calib, voxel_size=0.01)
    result = pipeline.process_frame(frames[0])
    with pytest.raises(ImportError, match="pip install rerun-sdk"):
        pipeline.log_to_rerun(result, frames[0])


@pytest.fixture(scope="module")
def rr():
    return pytest.importorskip("rerun")


def rows_per_entity(path):
    chunk = pytest.importorskip("rerun.chunk", reason="reading an .rrd back needs rerun.chunk (rerun-sdk 0.29+)")
    rows = {}
    for c in chunk.RrdReader(str(path)).stream().to_chunks():
        if not c.is_static:
            rows[str(c.entity_path)] = rows.get(str(c.entity_path), 0) + c.num_rows
    return rows


def blueprint_views(path):
    """The names of the views in the blueprint an .rrd file carries."""
    chunk = pytest.importorskip("rerun.chunk", reason="reading an .rrd back needs rerun.chunk (rerun-sdk 0.29+)")
    reader = chunk.RrdReader(str(path))
    names = set()
    for store in reader.blueprints():
        for c in reader.stream(store=store).to_chunks():
            batch = c.to_record_batch()
            if "ViewBlueprint:display_name" in batch.schema.names:
                names.update(n for row in batch.column("ViewBlueprint:display_name").to_pylist() for n in row)
    return names


def test_a_run_logs_pose_frustum_images_raycast_scalars_and_meshes(tmp_path, room_frames, rr):
    source, frames = room_frames
    pipeline = voxfuse.Pipeline(source.calib, voxel_size=0.01)
    recording = rr.RecordingStream("voxfuse_test")
    path = tmp_path / "run.rrd"
    recording.save(str(path))
    for frame in frames[:FRAMES]:
        result = pipeline.process_frame(frame)
        pipeline.log_to_rerun(result, frame, recording=recording, mesh_every=MESH_EVERY)
    recording.flush()
    del recording
    rows = rows_per_entity(path)
    for entity in (
        "/world/camera",
        "/world/camera/image/depth",
        "/world/camera/image/rgb",
        "/world/camera/image/raycast",
        "/tracking/inlier_ratio",
        "/tracking/quality",
        "/timings/total",
    ):
        assert rows.get(entity) == FRAMES, (entity, rows)
    assert rows.get("/world/mesh") == FRAMES // MESH_EVERY  # frames 0 and 3
    assert rows.get("/world/trajectory") == 1  # with the mesh of frame 3: frame 0's path is one point


def test_the_entry_point_saves_an_rrd_headless(tmp_path, rr):
    out = tmp_path / "out"
    rrd = tmp_path / "run.rrd"
    run = subprocess.run(
        [sys.executable, "-m", "voxfuse", str(SYNTHETIC_ROOM), "--out", str(out), "--frames", "4",
         "--set", "voxel_size=0.01", "--rerun", str(rrd), "--rerun-mesh-every", "2"],
        capture_output=True, text=True, timeout=300,
    )
    assert run.returncode == 0, run.stderr
    rows = rows_per_entity(rrd)
    assert rows.get("/world/camera") == 4
    assert rows.get("/world/mesh") == 3  # frames 0 and 2, and the final map
    assert rows.get("/world/trajectory") == 2
    assert blueprint_views(rrd) >= {"map", "colour", "depth", "raycast", "tracking", "stage ms"}
    assert np.loadtxt(out / "trajectory.txt").shape == (4, 8)


def test_a_colour_camera_apart_from_the_depth_camera_gets_its_own_frustum(tmp_path, room_frames, rr):
    source, frames = room_frames
    calib = source.calib
    calib.rgb = voxfuse.Intrinsics(320, 240, 262.5, 262.5, 159.75, 119.75)
    T = np.eye(4)
    T[0, 3] = 0.025
    calib.T_depth_rgb = T
    frame = voxfuse.Frame(frames[0].depth, frames[0].rgb[::2, ::2], calib=calib)
    pipeline = voxfuse.Pipeline(calib, voxel_size=0.01)
    recording = rr.RecordingStream("voxfuse_test")
    path = tmp_path / "two_cameras.rrd"
    recording.save(str(path))
    pipeline.log_to_rerun(pipeline.process_frame(frame), frame, recording=recording, mesh_every=0)
    recording.flush()
    del recording
    rows = rows_per_entity(path)
    assert rows.get("/world/camera/colour/rgb") == 1 and "/world/camera/image/rgb" not in rows
