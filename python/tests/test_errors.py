"""Wrong input is an exception that says what is wrong: TypeError for a dtype, ValueError for a shape,
and the library's errors as voxfuse exceptions (IoError is an OSError, ConfigError a ValueError)."""

import threading
import time

import numpy as np
import pytest

import voxfuse


@pytest.fixture
def pipeline(room_frames):
    source, _ = room_frames
    return voxfuse.Pipeline(source.calib, voxel_size=0.01)


def test_wrong_dtypes_are_type_errors(pipeline, room_frames):
    f = room_frames[1][0]
    with pytest.raises(TypeError, match="depth must be uint16 .* or float32/float64"):
        pipeline.process(f.depth.astype(np.int32))
    with pytest.raises(TypeError, match="depth must be a numpy array"):
        pipeline.process(f.depth.tolist())
    with pytest.raises(TypeError, match="rgb must be uint8"):
        pipeline.process(f.depth, f.rgb.astype(np.float32))
    with pytest.raises(TypeError, match="labels must be uint16"):
        pipeline.process(f.depth, labels=f.labels.astype(np.int64))
    with pytest.raises(TypeError, match="depth_scale applies to uint16 depth"):
        pipeline.process(f.depth.astype(np.float32), depth_scale=0.001)
    assert pipeline.frames_processed == 0, "a rejected frame is not processed"


def test_wrong_shapes_are_value_errors(pipeline, room_frames):
    f = room_frames[1][0]
    with pytest.raises(ValueError, match=r"depth must be of shape \(480, 640\) for this calibration, not \(640, 480\)"):
        pipeline.process(np.ascontiguousarray(f.depth.T))
    with pytest.raises(ValueError, match=r"rgb must be of shape \(480, 640, 3 or 4\)"):
        pipeline.process(f.depth, f.rgb[:, :, :2])
    with pytest.raises(ValueError, match="labels must be a 2-D"):
        pipeline.process(f.depth, labels=f.labels[None])
    with pytest.raises(ValueError, match="pose must be a 4x4 matrix"):
        pipeline.process(f.depth, pose=np.eye(3))
    with pytest.raises(ValueError, match="not finite"):
        pipeline.process(f.depth, pose=np.full((4, 4), np.nan))
    assert pipeline.frames_processed == 0


def test_library_errors_carry_the_message(room_frames, tmp_path):
    calib = room_frames[0].calib
    with pytest.raises(voxfuse.IoError, match="nowhere") as e:
        voxfuse.open_source(str(tmp_path / "nowhere"))
    assert isinstance(e.value, OSError) and isinstance(e.value, voxfuse.Error)
    with pytest.raises(voxfuse.ConfigError, match="unknown voxel type 'x'") as e:
        voxfuse.Pipeline(calib, voxel="x")
    assert isinstance(e.value, ValueError)
    with pytest.raises(TypeError, match="unknown setting 'voxelsize'"):
        voxfuse.Pipeline(calib, voxelsize=0.01)
    with pytest.raises(TypeError, match="setting 'voxel_size' cannot be 'big'"):
        voxfuse.Settings(voxel_size="big")
    with pytest.raises(voxfuse.Error, match="Pipeline settings: iterations: expected 1 or 3 values"):
        voxfuse.Pipeline(calib, tracker_iterations=[5, 5])
    with pytest.raises(voxfuse.ConfigError, match="render mode"):
        voxfuse.Pipeline(calib, voxel_size=0.01).render("fancy")
    bad = tmp_path / "bad.vfm"
    bad.write_bytes(b"not a map")
    with pytest.raises(voxfuse.IoError, match="bad.vfm"):
        voxfuse.Pipeline.from_map(str(bad))
    calib_file = tmp_path / "calib.txt"
    calib_file.write_text("640 480\nfive\n")
    with pytest.raises(voxfuse.IoError, match="calib.txt"):
        voxfuse.Calibration.from_file(str(calib_file))
    if not voxfuse.cuda_available():
        with pytest.raises(voxfuse.Error, match="(?i)cuda|gpu"):
            voxfuse.Pipeline(calib, device="cuda")


def test_the_gil_is_released_while_a_frame_is_processed(room_frames):
    source, frames = room_frames
    p = voxfuse.Pipeline(source.calib, voxel_size=0.01)
    done = threading.Event()
    worker_ms = []

    def work():
        for f in frames[:3]:
            worker_ms.append(p.process_frame(f).timings["total"])
        done.set()

    ticks = 0
    t = threading.Thread(target=work)
    t.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    t.join()
    # Holding the GIL, the worker would let this loop run only between frames (a handful of ticks);
    # released, the loop ticks about once a millisecond throughout.
    assert ticks > 0.3 * sum(worker_ms), (ticks, worker_ms)


def test_a_pipeline_busy_in_another_thread_says_so(room_frames):
    source, frames = room_frames
    p = voxfuse.Pipeline(source.calib, voxel_size=0.01)
    p.process_frame(frames[0])
    done = threading.Event()

    def work():
        for f in frames[1:4]:
            p.process_frame(f)
        done.set()

    t = threading.Thread(target=work)
    t.start()
    refused = served = 0
    while not done.is_set():
        try:
            p.render("shaded")
            served += 1
        except voxfuse.Error as e:
            assert "in use by another thread" in str(e)
            refused += 1
        time.sleep(0.001)
    t.join()
    assert refused > 0, "calls while a frame is processed are refused, not run alongside it"
    assert p.frames_processed == 4


def test_a_thread_count_out_of_range_is_refused():
    with pytest.raises(voxfuse.ConfigError, match="thread count"):
        voxfuse.set_cpu_threads(-1)
    assert voxfuse.cpu_threads() >= 1
