"""Arrays across the boundary: dtype, shape, strides, who owns the memory, and that what goes in
as uint16, metres, RGB or RGBA, contiguous or strided, gives the same map."""

import gc

import numpy as np
import pytest

import voxfuse


def test_frame_arrays_view_the_decoded_images(room_frames):
    source, frames = room_frames
    f = frames[0]
    k = source.calib.depth
    assert f.depth.dtype == np.uint16 and f.depth.shape == (k.height, k.width)
    assert f.depth.flags.c_contiguous and not f.depth.flags.owndata
    assert f.rgb.dtype == np.uint8 and f.rgb.shape == (k.height, k.width, 3)
    assert f.rgb.strides == (4 * k.width, 4, 1)  # RGB seen through RGBA pixels, no copy
    assert np.shares_memory(f.depth, f.depth)
    a, b = f.depth, f.depth
    assert np.shares_memory(a, b), "two reads of a frame's depth must view the same memory"
    assert (f.depth > 0).mean() > 0.5
    assert f.ground_truth_pose.shape == (4, 4)
    assert f.labels is not None and f.labels.dtype == np.uint16


def test_arrays_outlive_their_frame_and_source():
    source = voxfuse.open_source(str(__import__("conftest").SYNTHETIC_ROOM))
    frame = next(iter(source))
    depth, rgb = frame.depth, frame.rgb
    expected = depth.copy(), rgb.copy()
    del frame, source
    gc.collect()
    np.testing.assert_array_equal(depth, expected[0])
    np.testing.assert_array_equal(rgb, expected[1])


def test_mesh_and_cloud_arrays_are_consistent_and_owned(room_frames):
    source, frames = room_frames
    p = voxfuse.Pipeline(source.calib, voxel_size=0.01)
    for f in frames[:4]:
        p.process_frame(f, pose=f.ground_truth_pose)
    mesh = p.extract_mesh()
    v, t, n, c = mesh.vertices, mesh.faces, mesh.normals, mesh.colors
    assert v.dtype == np.float32 and v.ndim == 2 and v.shape[1] == 3 and len(v) > 1000
    assert t.dtype == np.int32 and t.shape[1] == 3 and t.min() >= 0 and t.max() < len(v)
    assert n.shape == v.shape and np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-3)
    assert c.dtype == np.uint8 and c.shape == v.shape
    assert mesh.labels is None  # s_rgb has no classes
    assert len(np.unique(v, axis=0)) == len(v), "no duplicate vertices"
    cloud = p.extract_point_cloud()
    assert len(cloud) == len(v)  # one point per zero-crossing edge, as the mesh's vertices
    np.testing.assert_array_equal(np.sort(cloud.points, axis=0), np.sort(v, axis=0))
    del p, mesh, cloud
    gc.collect()
    assert np.isfinite(v).all() and t.max() < len(v)  # still valid: the arrays own their mesh


def _run(calib, frames, to_depth, to_rgb, depth_scale=None, depth_of=None):
    p = voxfuse.Pipeline(calib, voxel_size=0.01)
    for f in frames:
        p.process((depth_of or to_depth)(f), to_rgb(f), depth_scale=depth_scale, pose=f.ground_truth_pose)
    return p.extract_mesh()


def test_depth_in_metres_and_rgba_give_the_same_map_as_raw_and_rgb(room_frames):
    source, frames = room_frames
    calib, scale = source.calib, source.calib.depth_scale
    reference = _run(calib, frames[:3], lambda f: f.depth, lambda f: f.rgb)
    metres = _run(calib, frames[:3], lambda f: f.depth.astype(np.float32) * np.float32(scale),
                  lambda f: np.concatenate([f.rgb, np.full(f.rgb.shape[:2] + (1,), 255, np.uint8)], axis=2))
    np.testing.assert_array_equal(reference.faces, metres.faces)
    np.testing.assert_array_equal(reference.vertices, metres.vertices)
    np.testing.assert_array_equal(reference.colors, metres.colors)
    # Raw depth in other units (millimetres here) with its scale: the same map.
    millimetres = _run(calib, frames[:3], lambda f: None, lambda f: f.rgb, depth_scale=0.001,
                       depth_of=lambda f: np.round(f.depth.astype(np.float64) * scale * 1000).astype(np.uint16))
    assert abs(len(millimetres.faces) - len(reference.faces)) < 0.02 * len(reference.faces)


def test_strided_inputs_are_read_as_their_values(room_frames):
    source, frames = room_frames
    reference = _run(source.calib, frames[:2], lambda f: f.depth, lambda f: f.rgb)
    # Fortran-ordered copies: same values, other strides.
    strided = _run(source.calib, frames[:2], lambda f: np.asfortranarray(f.depth), lambda f: np.asfortranarray(f.rgb))
    np.testing.assert_array_equal(reference.vertices, strided.vertices)
    np.testing.assert_array_equal(reference.colors, strided.colors)


def test_process_and_process_frame_agree(room_frames):
    source, frames = room_frames
    a = voxfuse.Pipeline(source.calib, voxel_size=0.01)
    b = voxfuse.Pipeline(source.calib, voxel_size=0.01)
    for f in frames[:4]:
        ra = a.process(f.depth, f.rgb, timestamp=f.timestamp)
        rb = b.process_frame(f)
        np.testing.assert_array_equal(ra.pose, rb.pose)
    np.testing.assert_array_equal(a.trajectory[1], b.trajectory[1])


def test_renders(room_frames):
    source, frames = room_frames
    p = voxfuse.Pipeline(source.calib, voxel_size=0.01)
    for f in frames[:2]:
        p.process_frame(f, pose=f.ground_truth_pose)
    k = source.calib.depth
    for mode in ("shaded", "color", "normals", "depth", "class"):
        img = p.render(mode)
        assert img.dtype == np.uint8 and img.shape == (k.height, k.width, 3)
    last = p.render("shaded")
    again = p.render("shaded", pose=frames[1].ground_truth_pose)
    assert (np.abs(last.astype(int) - again.astype(int)) > 2).mean() < 0.01, "a new raycast from the last pose shows the same"
    small = p.render("depth", pose=frames[1].ground_truth_pose, intrinsics=voxfuse.Intrinsics(160, 120, 131.25, 131.25, 79.5, 59.5))
    assert small.shape == (120, 160, 3)
    assert (last.sum(axis=2) > 0).mean() > 0.3


def test_a_frame_made_from_arrays_holds_them_and_is_checked_against_the_calibration(room_frames):
    source, frames = room_frames
    f = frames[3]
    made = voxfuse.Frame(f.depth, f.rgb, calib=source.calib, index=7, timestamp=2.5)
    assert np.array_equal(made.depth, f.depth) and np.array_equal(made.rgb, f.rgb)
    assert (made.index, made.timestamp, made.labels, made.ground_truth_pose) == (7, 2.5, None, None)
    assert voxfuse.Frame(f.depth, calib=source.calib, index=30).timestamp == 1.0  # index / 30
    metres = voxfuse.Frame(f.depth * source.calib.depth_scale, calib=source.calib)
    assert np.abs(metres.depth.astype(int) - f.depth).max() <= 1
    with pytest.raises(ValueError, match="shape"):
        voxfuse.Frame(f.depth[:, :100], calib=source.calib)
    with pytest.raises(TypeError):
        voxfuse.Frame(f.depth.astype(np.int32), calib=source.calib)
    with pytest.raises(ValueError, match="index"):
        voxfuse.Frame(f.depth, calib=source.calib, index=-1)
    with pytest.raises(ValueError, match="finite"):
        voxfuse.Frame(f.depth, calib=source.calib, timestamp=float("nan"))
