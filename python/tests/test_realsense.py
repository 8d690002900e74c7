"""RealSense input without a camera: the bundled room recorded through a librealsense software device,
read back, and reconstructed as the same frames are from the TUM folder."""

import sys

import numpy as np
import pytest

import voxfuse
from voxfuse import realsense

from conftest import SYNTHETIC_ROOM

FRAMES = 30


def test_without_pyrealsense2_the_error_says_how_to_install_it(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "pyrealsense2", None)  # import fails as when it is not installed
    with pytest.raises(ImportError, match="pip install pyrealsense2"):
        voxfuse.open_source(str(tmp_path / "walk.bag"))


def test_realsense_input_is_recognised_by_its_name():
    for path in ("a.bag", "dir/A.BAG", "b.db3", "realsense:", "realsense:123456"):
        assert realsense.handles(path), path
    for path in ("a.oni", "bag", "room/", "realsensex"):
        assert not realsense.handles(path), path


@pytest.fixture(scope="module")
def suffix():
    """What this librealsense records: ROS 2 bags (.db3) from 2.57 on, ROS 1 .bag before."""
    rs = pytest.importorskip("pyrealsense2")
    return ".db3" if tuple(int(v) for v in rs.__version__.split(".")[:2]) >= (2, 57) else ".bag"


def room(frames=FRAMES):
    source = voxfuse.open_source(str(SYNTHETIC_ROOM))
    return source, [f for _, f in zip(range(frames), source)]


@pytest.fixture(scope="module")
def recorded(tmp_path_factory, suffix):
    source, frames = room()
    path = tmp_path_factory.mktemp("realsense") / ("room" + suffix)
    assert realsense.write_recording(path, frames, source.calib) == FRAMES
    return path, source, frames


def test_a_recording_reads_back_bit_for_bit_with_its_calibration(recorded):
    path, tum, frames = recorded
    with voxfuse.open_source(str(path)) as source:
        got = list(source)
        assert source.dropped_frames == 0 and source.dropped_color_frames == 0
        calib = source.calib
    assert len(got) == FRAMES
    for want, have in zip(frames, got):
        assert np.array_equal(want.depth, have.depth), want.index
        assert np.array_equal(want.rgb, have.rgb), want.index
        assert have.timestamp == pytest.approx(want.timestamp, abs=1e-6)
        assert have.index == want.index
    for camera in ("depth", "rgb"):
        a, b = getattr(calib, camera), getattr(tum.calib, camera)
        assert (a.width, a.height) == (b.width, b.height)
        assert [a.fx, a.fy, a.cx, a.cy] == pytest.approx([b.fx, b.fy, b.cx, b.cy], abs=1e-4)
    assert calib.depth_scale == pytest.approx(tum.calib.depth_scale, rel=1e-6)
    assert np.allclose(calib.T_depth_rgb, np.eye(4), atol=1e-6)


def test_it_reconstructs_as_the_same_frames_from_the_tum_folder(recorded):
    path, tum, frames = recorded
    ate = {}
    for name, source in (("tum", voxfuse.open_source(str(SYNTHETIC_ROOM))), ("realsense", voxfuse.open_source(str(path)))):
        pipeline = voxfuse.Pipeline(source.calib)
        for _, frame in zip(range(FRAMES), source):
            assert pipeline.process_frame(frame).fused
        timestamps, poses = pipeline.trajectory
        gt_t, gt_poses = tum.ground_truth
        ate[name] = (poses, voxfuse.evaluate_trajectory(timestamps, poses, gt_t, gt_poses)["ate_rmse_m"])
        if hasattr(source, "close"):
            source.close()
    # The same pixels, the same calibration to float precision: the same trajectory.
    assert np.allclose(ate["tum"][0], ate["realsense"][0], atol=1e-6)
    assert ate["realsense"][1] == pytest.approx(ate["tum"][1], abs=1e-5)
    assert ate["realsense"][1] < 0.005


def test_the_color_camera_and_the_extrinsics_come_from_the_streams(tmp_path, suffix):
    # Colour at half the resolution, 25 mm to the side and turned 2 degrees: what a D435 looks like.
    tum, frames = room(3)
    calib = tum.calib
    calib.rgb = voxfuse.Intrinsics(320, 240, 262.5, 262.5, 159.75, 119.75)
    angle = np.radians(2.0)
    T = np.eye(4)
    T[:3, :3] = [[np.cos(angle), 0, np.sin(angle)], [0, 1, 0], [-np.sin(angle), 0, np.cos(angle)]]
    T[:3, 3] = [0.025, 0.0, 0.0]
    calib.T_depth_rgb = T
    half = [voxfuse.Frame(f.depth, f.rgb[::2, ::2], calib=calib, index=f.index, timestamp=f.timestamp) for f in frames]
    path = tmp_path / ("d435" + suffix)
    realsense.write_recording(path, half, calib)

    with voxfuse.open_source(str(path)) as raw:
        assert np.allclose(raw.calib.T_depth_rgb, T, atol=1e-6)
        assert (raw.calib.rgb.width, raw.calib.rgb.fx) == (320, pytest.approx(262.5))
        frame = next(raw)
        assert frame.depth.shape == (480, 640) and frame.rgb.shape == (240, 320, 3)
    with voxfuse.open_source(str(path), align="color") as to_color:
        assert (to_color.calib.depth.width, to_color.calib.depth.fx) == (320, pytest.approx(262.5))
        frame = next(to_color)
        assert frame.depth.shape == (240, 320) and frame.rgb.shape == (240, 320, 3)
        assert (frame.depth > 0).mean() > 0.5  # depth resampled into the colour camera, not lost
        # librealsense's own resampling puts each depth sample where VoxFuse's T_depth_rgb says it lies:
        # the extrinsics mean the same to both (read the wrong way round, samples move ~20 px). rs.align
        # keeps the depth camera's z, so the values are compared as they were.
        d, k, c = frames[0].depth.astype(np.float64) * calib.depth_scale, calib.depth, calib.rgb
        v, u = np.nonzero(d > 0)
        z = d[v, u]
        p_depth = np.stack([(u - k.cx) / k.fx * z, (v - k.cy) / k.fy * z, z, np.ones_like(z)])
        p_rgb = np.linalg.inv(T) @ p_depth
        uc = np.rint(c.fx * p_rgb[0] / p_rgb[2] + c.cx).astype(int)
        vc = np.rint(c.fy * p_rgb[1] / p_rgb[2] + c.cy).astype(int)
        inside = (uc >= 0) & (uc < 320) & (vc >= 0) & (vc < 240)
        aligned = frame.depth[vc[inside], uc[inside]] * calib.depth_scale
        agree = np.abs(aligned - z[inside]) < 0.01 * z[inside]
        assert agree.mean() > 0.75, agree.mean()  # 0.84; the rest: rs.align's footprints at half size, edges
    with voxfuse.open_source(str(path), align="depth") as to_depth:
        assert np.allclose(to_depth.calib.T_depth_rgb, np.eye(4))
        frame = next(to_depth)
        assert frame.depth.shape == (480, 640) and frame.rgb.shape == (480, 640, 3)
        assert np.array_equal(frame.depth, frames[0].depth)  # depth untouched
        assert (frame.rgb.sum(axis=2) > 0).mean() > 0.5


def test_frames_missing_from_the_recording_are_counted_as_dropped(tmp_path, suffix):
    tum, frames = room(8)
    kept = [f for f in frames if f.index not in (3, 4, 6)]
    path = tmp_path / ("gaps" + suffix)
    realsense.write_recording(path, kept, tum.calib)
    with voxfuse.open_source(str(path)) as source:
        got = list(source)
        assert len(got) == 5 and source.dropped_frames == 3 and source.dropped_color_frames == 3
    assert [f.timestamp for f in got] == pytest.approx([f.timestamp for f in kept], abs=1e-6)


def test_breaking_off_early_stops_the_player(recorded):
    path, _, _ = recorded
    source = voxfuse.open_source(str(path))
    assert next(source).index == 0
    source.close()  # returns: the player's thread, blocked on the full queue, is released
    assert list(source) == []


def test_bad_recordings_and_options_are_refused_with_the_reason(tmp_path, recorded, suffix):
    junk = tmp_path / ("junk" + suffix)
    junk.write_bytes(np.random.default_rng(0).integers(0, 256, 4096, dtype=np.uint8).tobytes())
    with pytest.raises(voxfuse.IoError, match="not a readable RealSense recording"):
        voxfuse.open_source(str(junk))
    with pytest.raises(voxfuse.IoError, match="not a readable RealSense recording"):
        voxfuse.open_source(str(tmp_path / ("missing" + suffix)))
    with pytest.raises(voxfuse.ConfigError, match="align must be one of"):
        voxfuse.open_source(str(recorded[0]), align="colour-ish")
    with pytest.raises(TypeError):
        voxfuse.open_source(str(recorded[0]), rgb="%04i.ppm")  # a PPM option means nothing here


def test_a_truncated_recording_ends_early_or_is_refused_never_hangs(tmp_path, recorded, suffix):
    data = recorded[0].read_bytes()
    cut = tmp_path / ("cut" + suffix)
    cut.write_bytes(data[: len(data) // 2])
    try:
        with voxfuse.open_source(str(cut)) as source:
            got = list(source)
    except voxfuse.IoError as e:
        assert "cut" in str(e)
        return
    assert len(got) < FRAMES
