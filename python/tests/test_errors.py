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
    with pytest.raises(ValueError, match="timestamp must be a finite number"):
        pipeline.process(f.depth, timestamp=float("nan"))  # it would key the trajectory
    assert pipeline.frames_processed == 0


def test_library_errors_carry_the_message(room_frames, tmp_path):
    calib = room_frames[0].calib
    with pytest.raises(voxfuse.IoError, match="nowhere") as e:
        voxfuse.open_source(str(tmp_path / "nowhere"))
    assert isinstance(e.value, OSError) and isinstance(e.value, voxfuse.Error)
    with pytest.raises(voxfuse.ConfigError, match="setting 'voxel': 'x' is not one of s, f, s_rgb") as e:
        voxfuse.Pipeline(calib, voxel="x")
    assert isinstance(e.value, ValueError)
    with pytest.raises(TypeError, match="unknown setting 'voxelsize'"):
        voxfuse.Pipeline(calib, voxelsize=0.01)
    with pytest.raises(TypeError, match="setting 'voxel_size' cannot be 'big'"):
        voxfuse.Settings(voxel_size="big")
    with pytest.raises(voxfuse.Error, match="tracker settings: iterations: expected 1 or 3 values"):
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


def test_readers_on_another_thread_get_the_data_or_a_refusal(room_frames):
    # The trajectory, summary and pose are copied from what process_frame appends to: read while a
    # frame is processed, they are refused (the heap was corrupted before), never torn.
    source, frames = room_frames
    p = voxfuse.Pipeline(source.calib, voxel="s", voxel_size=0.05, mu=0.2)
    done = threading.Event()
    reads = {"served": 0, "refused": 0}

    def reader():
        while not done.is_set():
            for read in (lambda: p.trajectory, p.summary, lambda: p.pose, p.timings):
                try:
                    read()
                    reads["served"] += 1
                except voxfuse.Error as e:
                    assert "in use by another thread" in str(e)
                    reads["refused"] += 1

    t = threading.Thread(target=reader)
    t.start()
    for _ in range(3):
        for f in frames:
            p.process_frame(f)
    done.set()
    t.join()
    assert p.frames_processed == 3 * len(frames)
    assert len(p.trajectory[0]) == 3 * len(frames)
    assert reads["refused"] > 0, reads


def test_labels_for_a_map_without_classes_are_refused(pipeline, room_frames):
    f = room_frames[1][0]
    with pytest.raises(voxfuse.ConfigError, match="labels need a voxel type with classes"):
        pipeline.process(f.depth, f.rgb, f.labels)
    assert pipeline.frames_processed == 0


def test_a_pose_that_is_no_camera_pose_is_refused(room_frames):
    source, frames = room_frames
    p = voxfuse.Pipeline(source.calib, voxel_size=0.02, mu=0.08)
    scaled = np.diag([3.0, 3.0, 3.0, 1.0])
    sheared = np.eye(4)
    sheared[0, 1] = 0.5
    for pose in (scaled, sheared):
        with pytest.raises(voxfuse.ConfigError, match="no camera pose: the pose's rotation is not a rotation"):
            p.process_frame(frames[0], pose=pose)
        with pytest.raises(voxfuse.ConfigError, match="no camera pose"):
            p.render("shaded", pose=pose)
    assert p.frames_processed == 0


def test_an_rgb_view_of_rgba_pixels_is_not_read_past_its_end(tmp_path):
    # The view's last pixel ends 1 byte before its RGBA pixel does: with the buffer's end against a
    # page that may not be read, copying whole 4-byte pixels crashed. Run apart: a crash is a failure here.
    script = tmp_path / "guard.py"
    script.write_text(
        "import ctypes, mmap\n"
        "import numpy as np\n"
        "import voxfuse\n"
        "H, W = 48, 64\n"
        "page = mmap.PAGESIZE\n"
        "n = -(-H * W * 4 // page) * page\n"
        "buf = mmap.mmap(-1, n + page)\n"
        "libc = ctypes.CDLL(None)\n"
        "libc.mprotect.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int]\n"
        "addr = ctypes.addressof(ctypes.c_char.from_buffer(buf))\n"
        "assert libc.mprotect(addr + n, page, 0) == 0\n"
        "pixels = np.frombuffer(buf, dtype=np.uint8, count=n)[n - H * W * 4:].reshape(H, W, 4)\n"
        "pixels[:] = 100\n"
        "calib = voxfuse.Calibration.pinhole(W, H, 52.5, 52.5, 31.5, 23.5)\n"
        "p = voxfuse.Pipeline(calib, voxel_size=0.05, mu=0.2)\n"
        "p.process(np.full((H, W), 1000, np.uint16), pixels[:, :, 1:4])\n"
        "print('ok')\n")
    import subprocess
    import sys
    run = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0 and run.stdout.strip() == "ok", (run.returncode, run.stderr[-2000:])


def test_a_source_read_by_two_threads_refuses_the_second(room_source):
    # The GIL is released while a frame decodes: a second thread reading the same source is refused
    # (both at once corrupted the frame buffers), and every frame still arrives once.
    indices, refused = [], []

    def read():
        while True:
            try:
                indices.append(next(room_source).index)
            except StopIteration:
                return
            except voxfuse.Error as e:
                assert "being read by another thread" in str(e)
                refused.append(1)

    threads = [threading.Thread(target=read) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(indices) == list(range(len(room_source)))
    assert refused, "the two threads never overlapped"


def test_a_thread_count_out_of_range_is_refused():
    with pytest.raises(voxfuse.ConfigError, match="thread count"):
        voxfuse.set_cpu_threads(-1)
    assert voxfuse.cpu_threads() >= 1
