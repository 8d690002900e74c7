"""The pipeline on real data: the bundled room against its ground truth, maps saved and continued,
and the same mesh as the command line from the same frames."""

import os
import pathlib
import subprocess

import numpy as np
import pytest

import voxfuse
from conftest import SHARED_DATA, SYNTHETIC_ROOM


def test_bundled_sequence_is_tracked_against_its_ground_truth(room_source):
    p = voxfuse.Pipeline(room_source.calib)  # the command line's defaults
    for i, frame in enumerate(room_source):
        r = p.process_frame(frame)
        assert r.quality != "failed", f"frame {frame.index}"
        if i == 29:
            break
    t, poses = p.trajectory
    gt_t, gt_poses = room_source.ground_truth
    err = voxfuse.evaluate_trajectory(t, poses, gt_t, gt_poses)
    assert err["pairs"] == 30
    assert err["ate_rmse_m"] < 0.005
    s = p.summary()
    assert s["frames"] == 30 and s["frames_fused"] == 30 and s["device"] == "cpu"
    assert set(s["stages"]) >= {"depth", "track", "allocate", "integrate", "raycast", "total"}
    assert s["stages"]["total"]["frames"] == 30 and s["stages"]["total"]["median_ms"] > 0


def test_trajectory_error_finds_a_clock_that_lags():
    # Ground truth at 100 Hz on a path where a time shift is no rigid motion; the camera's poses
    # exact at 25 Hz, stamped 30 ms late.
    t = np.arange(500) * 0.01
    poses = np.tile(np.eye(4), (len(t), 1, 1))
    poses[:, 0, 3], poses[:, 1, 3], poses[:, 2, 3] = t, 0.3 * np.sin(2 * t), 0.1 * t * t
    cam = np.arange(20, 480, 4)
    err = voxfuse.evaluate_trajectory(t[cam] + 0.03, poses[cam], t, poses)
    assert err["ate_rmse_m"] > 0.005
    assert abs(err["best_time_offset_s"] + 0.03) < 1e-6 and err["ate_rmse_at_best_time_offset_m"] < 1e-5
    at = voxfuse.evaluate_trajectory(t[cam] + 0.03, poses[cam], t, poses, time_offset=-0.03)
    assert at["ate_rmse_m"] < 1e-5
    assert np.isnan(voxfuse.evaluate_trajectory(t[cam], poses[cam], t, poses, max_time_offset=0)["best_time_offset_s"])
    with pytest.raises(voxfuse.ConfigError, match="at most 1 s"):
        voxfuse.evaluate_trajectory(t[cam], poses[cam], t, poses, max_time_offset=5.0)


def test_saved_map_continues_and_meshes_as_the_original(room_frames, tmp_path):
    source, frames = room_frames
    p = voxfuse.Pipeline(source.calib, voxel="s_rgb", voxel_size=0.01)
    for f in frames[:6]:
        p.process_frame(f)
    path = str(tmp_path / "room.vfm")
    p.save_map(path)
    q = voxfuse.Pipeline.from_map(path, source.calib)
    np.testing.assert_array_equal(p.pose, q.pose)
    a, b = p.extract_mesh(), q.extract_mesh()
    np.testing.assert_array_equal(a.vertices, b.vertices)
    np.testing.assert_array_equal(a.faces, b.faces)
    # The loaded map tracks the next frames as the original does (not to the bit: the original's tracker
    # also remembers the last frame's motion).
    T0_inv = np.linalg.inv(frames[0].ground_truth_pose)
    for f in frames[6:9]:
        truth = (T0_inv @ f.ground_truth_pose)[:3, 3]
        for pipeline in (p, q):
            assert np.linalg.norm(pipeline.process_frame(f).pose[:3, 3] - truth) < 0.003
    with pytest.raises(voxfuse.ConfigError, match="the map decides"):
        voxfuse.Pipeline.from_map(path, voxel_size=0.02)
    # The block ceiling bounds how far the map grows here: given, it replaces the map's.
    assert voxfuse.Pipeline.from_map(path, source.calib, max_blocks=300000).settings.max_blocks == 300000
    with pytest.raises(voxfuse.Error, match="larger --max-blocks"):
        voxfuse.Pipeline.from_map(path, source.calib, max_blocks=16)


def test_same_mesh_as_the_command_line(room_frames, tmp_path):
    cli = os.environ.get("VOXFUSE_CLI")
    if not cli:
        pytest.skip("VOXFUSE_CLI (the voxfuse program) is not set; ctest sets it")
    source, frames = room_frames
    out = tmp_path / "cli"
    subprocess.run([cli, str(SYNTHETIC_ROOM), "--frames", "8", "--poses", "groundtruth", "--voxel-size", "0.01", "--mesh",
                    "--out", str(out), "--render-every", "0"], check=True, capture_output=True)
    p = voxfuse.Pipeline(source.calib, voxel_size=0.01)
    for f in frames[:8]:
        p.process_frame(f, ground_truth=True)
    mesh_path = tmp_path / "python.ply"
    p.extract_mesh().save(str(mesh_path))
    assert mesh_path.read_bytes() == (out / "mesh.ply").read_bytes()


@pytest.mark.skipif(not (SHARED_DATA / "tum_fr3_teddy_200").is_dir(), reason="../shared/data/tum_fr3_teddy_200 is not beside the checkout")
def test_teddy_first_frames_track_within_a_centimetre():
    source = voxfuse.open_source(str(SHARED_DATA / "tum_fr3_teddy_200"))
    p = voxfuse.Pipeline(source.calib, voxel="s")
    for i, frame in enumerate(source):
        p.process_frame(frame)
        if i == 39:
            break
    err = voxfuse.evaluate_trajectory(*p.trajectory, *source.ground_truth)
    assert err["pairs"] >= 30 and err["ate_rmse_m"] < 0.01  # TUM's ground truth misses some frames' times


def test_the_map_does_not_depend_on_the_cpu_thread_count(room_frames, tmp_path):
    source, frames = room_frames
    meshes = []
    try:
        for threads in (1, 3):
            voxfuse.set_cpu_threads(threads)
            assert voxfuse.cpu_threads() == threads
            p = voxfuse.Pipeline(source.calib, voxel_size=0.01)
            for f in frames[:6]:
                p.process_frame(f)
            path = tmp_path / f"mesh_{threads}.ply"
            p.extract_mesh().save(str(path))
            meshes.append((path.read_bytes(), p.trajectory[1]))
    finally:
        voxfuse.set_cpu_threads(0)
    assert voxfuse.cpu_threads() >= 1
    assert meshes[0][0] == meshes[1][0]
    np.testing.assert_array_equal(meshes[0][1], meshes[1][1])


def run_with_covered_lens(source, frames, **settings):
    """Frames 0-5 as recorded, 6-8 with no depth at all (a covered lens), then 9-11 as recorded."""
    p = voxfuse.Pipeline(source.calib, voxel_size=0.01, **settings)
    results = []
    for i, f in enumerate(frames):
        if 6 <= i <= 8:
            results.append(p.process(np.zeros_like(f.depth), f.rgb, timestamp=f.timestamp))
        else:
            results.append(p.process_frame(f))
    return p, results


def test_a_covered_lens_is_lost_then_found_again(room_frames):
    source, frames = room_frames
    p, results = run_with_covered_lens(source, frames)
    assert [r.status for r in results] == ["tracking"] * 6 + ["lost"] * 3 + ["relocalised"] + ["tracking"] * 2
    for r in results[6:9]:
        assert r.quality == "failed" and not r.fused
        assert not r.relocalisation_tried  # a frame without depth is not worth the candidates
        np.testing.assert_array_equal(r.pose, results[5].pose)  # the last good pose
    assert results[9].relocalisation_tried and results[9].fused
    assert results[0].keyframes == 1 and results[-1].keyframes >= 1
    assert "relocalised" in repr(results[9]) and "lost" in repr(results[6])
    s = p.summary()
    assert (s["frames_lost"], s["relocalisation_attempts"], s["relocalisations"]) == (3, 1, 1)
    # Lost frames have no pose of their own: the trajectory leaves them out, as the CLI's does.
    t, poses = p.trajectory
    np.testing.assert_array_equal(t, [f.timestamp for i, f in enumerate(frames) if not 6 <= i <= 8])
    err = voxfuse.evaluate_trajectory(t, poses, *source.ground_truth)
    assert err["pairs"] == 9 and err["ate_rmse_m"] < 0.005


def test_without_relocalisation_tracking_resumes_from_the_last_good_pose(room_frames):
    source, frames = room_frames
    p, results = run_with_covered_lens(source, frames, relocalise=False)
    assert [r.status for r in results] == ["tracking"] * 6 + ["lost"] * 3 + ["tracking"] * 3
    assert not any(r.relocalisation_tried for r in results) and results[-1].keyframes == 0
    s = p.summary()
    assert (s["frames_lost"], s["relocalisation_attempts"], s["relocalisations"]) == (3, 0, 0)
    assert p.settings.to_dict()["relocalise"] is False


def test_relocalisation_settings_are_checked():
    calib = voxfuse.open_source(str(SYNTHETIC_ROOM)).calib
    with pytest.raises(voxfuse.ConfigError, match=r"relocalise_candidates': 0 is not in \[1, 1000\]"):
        voxfuse.Pipeline(calib, relocalise_candidates=0)
    with pytest.raises(voxfuse.ConfigError, match="relocalise_max_speed': -1 is not in"):
        voxfuse.Pipeline(calib, relocalise_max_speed=-1.0)
    with pytest.raises(voxfuse.ConfigError, match="relocalise_min_color_correlation': 1.5 is not in"):
        voxfuse.Pipeline(calib, relocalise_min_color_correlation=1.5)
    off = voxfuse.Pipeline(calib, relocalise_min_color_correlation=-1.0)
    assert off.settings.to_dict()["relocalise_min_color_correlation"] == -1.0
    with pytest.warns(DeprecationWarning, match="relocalise_min_color_correlation"):
        former = voxfuse.Pipeline(calib, relocalise_min_colour_correlation=-1.0)  # the former spelling
    assert former.settings.relocalise_min_color_correlation == -1.0


def test_reset_forgets_the_ground_truth_origin(room_frames):
    # After a reset the next ground-truth frame defines the world again, as the first frame did.
    source, frames = room_frames
    p = voxfuse.Pipeline(source.calib, voxel_size=0.02, mu=0.08)
    for f in frames[:3]:
        p.process_frame(f, ground_truth=True)
    p.reset()
    p.process_frame(frames[6], ground_truth=True)
    assert np.allclose(p.pose, np.eye(4), atol=1e-6), p.pose


def test_submaps_expose_their_loops_and_optimised_trajectory(room_source, tmp_path):
    frames = []
    for frame in room_source:
        frames.append(frame)
        if len(frames) == 30:
            break
    single = voxfuse.Pipeline(room_source.calib)
    single.process_frame(frames[0])
    assert single.submap_count == 1 and single.loop_closures() == [] and single.submap_poses() == []
    assert single.pose_graph_solves() == {"solves": 0, "total_ms": 0.0, "max_ms": 0.0}
    np.testing.assert_array_equal(single.optimised_trajectory[1], single.trajectory[1])

    try:
        p = voxfuse.Pipeline(room_source.calib, voxfuse.Settings(submaps=True, submap_distance=0.1))
    except voxfuse.ConfigError as e:
        pytest.skip(str(e))  # a build without Ceres
    for i in list(range(30)) + list(range(28, -1, -1)):  # there and back
        p.process_frame(frames[i])
    assert p.submap_count >= 3
    submaps = p.submap_poses()
    assert len(submaps) == p.submap_count and submaps[0]["parent"] == -1
    np.testing.assert_allclose(submaps[0]["pose"], np.eye(4), atol=1e-6)
    assert all(0 <= s["parent"] < i for i, s in enumerate(submaps) if i > 0)
    assert all(s["pose"].shape == (4, 4) for s in submaps)
    loops = p.loop_closures()
    assert len(loops) >= 1
    assert all(not l["rejected"] and l["frame"] >= 30 and l["chi2"] < 22.46 for l in loops)
    solves = p.pose_graph_solves()
    assert solves["solves"] >= 1 and 0.0 < solves["max_ms"] <= solves["total_ms"]
    t, tracked = p.trajectory
    t_opt, optimised = p.optimised_trajectory
    np.testing.assert_array_equal(t, t_opt)
    assert optimised.shape == tracked.shape == (59, 4, 4)
    assert np.abs(optimised[:, :3, 3] - tracked[:, :3, 3]).max() < 0.01

    # The map of submaps saves and loads whole: its submaps at their poses, submaps on.
    path = str(tmp_path / "submaps.vfm")
    p.save_map(path)
    q = voxfuse.Pipeline.from_map(path, room_source.calib)
    assert q.settings.submaps and q.submap_count == p.submap_count
    for a, b in zip(p.submap_poses(), q.submap_poses()):
        assert a["parent"] == b["parent"]
        np.testing.assert_array_equal(a["pose"], b["pose"])

    # Another map of the same place, from the first 20 frames, joins it.
    r = voxfuse.Pipeline(room_source.calib, voxfuse.Settings(submaps=True, submap_distance=0.1))
    for i in range(20):
        r.process_frame(frames[i])
    joins = r.merge_map(path)
    assert joins and all(j["frame"] == -1 and j["residual_m"] < 0.006 for j in joins)
    assert r.submap_count > p.submap_count
