"""Intel RealSense input: recordings (.bag, .db3) and live cameras, through pyrealsense2.

    source = voxfuse.open_source("recording.bag")        # or "realsense:" (first camera), "realsense:SERIAL"
    pipeline = voxfuse.Pipeline(source.calib)            # the stream's own intrinsics and depth scale
    for frame in source:
        pipeline.process_frame(frame)
    print(source.dropped_frames)

pyrealsense2 is optional (`pip install pyrealsense2`, the official wrapper, which ships librealsense).
The calibration comes from the streams (no calib.txt): both cameras' intrinsics, the colour-to-depth
extrinsics and the depth sensor's depth units. ``align`` says how depth and colour meet:

- ``"none"`` (default): the images as the sensors took them; VoxFuse maps colour onto depth itself
  with the extrinsics, as it does for a Kinect calibration. No resampling of depth.
- ``"color"``: depth resampled into the colour camera (librealsense's rs.align); the frames then have
  the colour camera's geometry. rs.align keeps each sample's depth-camera z, exact when the cameras are
  parallel (a RealSense's are to a fraction of a degree).
- ``"depth"``: colour resampled into the depth camera; the frames have the depth camera's geometry.

Frames are paired by device timestamp (each depth frame with the colour frame nearest in time).
Frames missing from a stream's frame numbers are counted in ``dropped_frames`` (depth) and
``dropped_color_frames``: in a recording they were dropped when it was made, from a live camera
while the reconstruction lagged.
"""

import atexit
import math
import queue
import threading
import warnings
import weakref

import numpy as np

from . import _voxfuse

ALIGN_MODES = ("none", "color", "depth")
_LIVE_PREFIX = "realsense:"
_RECORDING_SUFFIXES = (".bag", ".db3")
_COLOR_FORMATS = {"rgb8": False, "bgr8": True, "rgba8": False, "bgra8": True}  # format: channels in BGR order
# Sources still open when the interpreter exits are closed first: a player thread left inside its
# callback while Python finalises aborts the process.
_open_sources = weakref.WeakSet()
atexit.register(lambda: [s.close() for s in list(_open_sources)])
# A recording whose player delivers nothing for this long is stuck, not slow: the player is paced by
# the reader (non-real-time playback), so even a slow reconstruction sees a frame every few ms.
_STALL_S = 20.0


def handles(path):
    """Whether `path` names RealSense input: a .bag/.db3 recording or realsense:[SERIAL]."""
    p = str(path)
    return p.startswith(_LIVE_PREFIX) or p.lower().endswith(_RECORDING_SUFFIXES)


def _import_rs(path):
    try:
        import pyrealsense2 as rs  # optional: only RealSense input needs it
    except ImportError as e:
        raise ImportError(
            f"{path}: RealSense input needs pyrealsense2, the official Python wrapper (it ships librealsense): "
            "pip install pyrealsense2"
        ) from e
    return rs


def _intrinsics(profile):
    return profile.as_video_stream_profile().get_intrinsics()


def _calibration(depth_k, color_k, depth_scale, T_depth_rgb, align):
    """A voxfuse.Calibration from rs.intrinsics (librealsense's pixel centres are at integers, as VoxFuse's)."""

    def pinhole(k):
        return _voxfuse.Calibration.pinhole(
            k.width, k.height, k.fx, k.fy, k.ppx, k.ppy, depth_scale=depth_scale
        )

    if align == "color":
        return pinhole(color_k)
    calib = pinhole(depth_k)
    if align == "none" and color_k is not None:
        calib.rgb = _voxfuse.Intrinsics(
            color_k.width, color_k.height, color_k.fx, color_k.fy, color_k.ppx, color_k.ppy
        )
        calib.T_depth_rgb = T_depth_rgb
    return calib


def _transform(extrinsics):
    """rs.extrinsics (rotation column-major, metres) as a 4x4 matrix."""
    T = np.eye(4)
    T[:3, :3] = np.asarray(extrinsics.rotation, dtype=np.float64).reshape(3, 3).T
    T[:3, 3] = extrinsics.translation
    return T


def _warn_distortion(name, k, align):
    if any(abs(c) > 0.0 for c in k.coeffs):
        advice = (
            "align='color' or 'depth' lets librealsense apply it"
            if align == "none"
            else "the aligned frames are treated as ideal pinhole images"
        )
        warnings.warn(
            f"RealSense {name} stream has lens distortion ({k.model}, {list(k.coeffs)}) that VoxFuse's "
            f"pinhole model ignores; {advice}",
            RuntimeWarning,
            stacklevel=3,
        )


class RealSenseSource:
    """Frames from a RealSense recording or camera, as voxfuse.Frame objects (see the module's help).

    Iterate it; ``calib`` is the voxfuse.Calibration of the frames it yields. Close it (or use it in a
    with-block) to stop the camera or the player early.
    """

    def __init__(self, path, *, align="none", width=640, height=480, fps=30, timeout_s=5.0):
        if align not in ALIGN_MODES:
            raise _voxfuse.ConfigError(f"align must be one of {', '.join(ALIGN_MODES)}, not {align!r}")
        for name, value in (("width", width), ("height", height), ("fps", fps)):
            if not isinstance(value, int) or value <= 0:
                raise _voxfuse.ConfigError(f"{name} must be a positive integer, not {value!r}")
        if not (isinstance(timeout_s, (int, float)) and math.isfinite(timeout_s) and timeout_s > 0):
            raise _voxfuse.ConfigError(f"timeout_s must be a positive number of seconds, not {timeout_s!r}")
        self._rs = _import_rs(path)
        self._path = str(path)
        self._align_mode = align
        self._timeout_s = float(timeout_s)
        self._closed = False
        self._next_index = 0
        self._last_number = {}
        self.dropped_frames = 0
        self.dropped_color_frames = 0
        self.unreadable_frames = 0
        self._aligner = None
        self._pairing = self._paired = self._pair = None  # recordings' frame sets for rs.align (_aligned)
        if align != "none":
            self._aligner = self._rs.align(self._rs.stream.color if align == "color" else self._rs.stream.depth)
        self._live = self._path.startswith(_LIVE_PREFIX)
        if self._live:
            self._open_camera(self._path[len(_LIVE_PREFIX) :], width, height, fps)
        else:
            self._open_recording(self._path)
        _open_sources.add(self)

    # --- opening ---------------------------------------------------------------------------------

    def _open_camera(self, serial, width, height, fps):
        rs = self._rs
        devices = rs.context().query_devices()
        serials = [d.get_info(rs.camera_info.serial_number) for d in devices]
        if not serials:
            raise _voxfuse.IoError("realsense: no RealSense camera is connected")
        if serial and serial not in serials:
            raise _voxfuse.IoError(f"realsense:{serial}: no such camera; connected: {', '.join(serials)}")
        config = rs.config()
        config.enable_device(serial or serials[0])
        config.enable_stream(rs.stream.depth, width, height, rs.format.z16, fps)
        config.enable_stream(rs.stream.color, width, height, rs.format.rgb8, fps)
        self._pipeline = rs.pipeline()
        try:
            profile = self._pipeline.start(config)
        except RuntimeError as e:
            raise _voxfuse.IoError(
                f"realsense:{serial or serials[0]}: cannot stream depth and colour at {width}x{height} "
                f"{fps} fps: {e}"
            ) from e
        depth_profile = profile.get_stream(rs.stream.depth)
        color_profile = profile.get_stream(rs.stream.color)
        scale = profile.get_device().first_depth_sensor().get_depth_scale()
        self._description = f"RealSense camera {serial or serials[0]}"
        self._set_calibration(depth_profile, color_profile, scale)

    def _open_recording(self, path):
        rs = self._rs
        try:
            device = rs.context().load_device(path)
        except RuntimeError as e:
            raise _voxfuse.IoError(f"{path}: not a readable RealSense recording: {e}") from e
        self._device = device
        self._player = device.as_playback()
        self._player.set_real_time(False)  # every frame, paced by the reader, none dropped by the player
        depth_profile = color_profile = None
        self._sensors = []
        depth_sensor = None
        for sensor in device.query_sensors():
            wanted = []
            for p in sensor.get_stream_profiles():
                if p.stream_type() == rs.stream.depth and p.format() == rs.format.z16 and depth_profile is None:
                    depth_profile, depth_sensor = p, sensor
                    wanted.append(p)
                elif p.stream_type() == rs.stream.color and color_profile is None:
                    color_profile = p
                    wanted.append(p)
            if wanted:
                self._sensors.append((sensor, wanted))
        if depth_profile is None:
            raise _voxfuse.IoError(f"{path}: the recording has no depth stream (Z16)")
        if color_profile is not None:
            fmt = str(color_profile.format()).split(".")[-1]
            if fmt not in _COLOR_FORMATS:
                raise _voxfuse.IoError(f"{path}: colour is recorded as {fmt}; VoxFuse reads {', '.join(_COLOR_FORMATS)}")
        elif self._align_mode != "none":
            raise _voxfuse.ConfigError(f"{path}: align={self._align_mode!r} needs a colour stream; it has none")
        try:
            scale = depth_sensor.as_depth_sensor().get_depth_scale()
        except RuntimeError:
            scale = 0.001  # librealsense's default unit when a recording does not carry one
            warnings.warn(f"{path}: no depth units recorded; taking 1 mm", RuntimeWarning, stacklevel=3)
        self._description = f"RealSense recording {path}"
        self._set_calibration(depth_profile, color_profile, scale)
        self._frames = queue.Queue(maxsize=4)
        self._stop = threading.Event()
        for sensor, profiles in self._sensors:
            sensor.open(profiles)
        # Paused while the sensors start, so that no sensor misses the recording's first frames.
        self._player.pause()
        for sensor, _ in self._sensors:
            sensor.start(self._on_recorded_frame)
        self._player.resume()
        self._pending_depth = []  # depth frames waiting for the colour frame after them
        self._ready = []  # pairs decided, in order
        self._previous_color = None
        self._ended = False

    def _set_calibration(self, depth_profile, color_profile, depth_scale):
        depth_k = _intrinsics(depth_profile)
        color_k = _intrinsics(color_profile) if color_profile is not None else None
        T_depth_rgb = np.eye(4)
        if color_profile is not None:
            T_depth_rgb = _transform(color_profile.get_extrinsics_to(depth_profile))
        self.calib = _calibration(depth_k, color_k, depth_scale, T_depth_rgb, self._align_mode)
        used = {"none": [("depth", depth_k), ("colour", color_k)], "color": [("colour", color_k)]}.get(
            self._align_mode, [("depth", depth_k)]
        )
        for name, k in used:
            if k is not None:
                _warn_distortion(name, k, self._align_mode)
        self._color_is_bgr = color_profile is not None and _COLOR_FORMATS.get(
            str(color_profile.format()).split(".")[-1], False
        )
        self._has_color = color_profile is not None

    # --- reading ---------------------------------------------------------------------------------

    def _on_recorded_frame(self, frame):
        # On the player's thread. Blocking here paces the player (non-real-time playback waits for
        # its callback), so the queue never overflows and no frame is lost; close() ends the wait.
        frame.keep()
        while not self._stop.is_set():
            try:
                self._frames.put(frame, timeout=0.1)
                return
            except queue.Full:
                continue

    def _count_drops(self, frame, is_depth):
        stream = "depth" if is_depth else "colour"
        number = frame.get_frame_number()
        last = self._last_number.get(stream)
        if last is not None and number > last + 1:
            if is_depth:
                self.dropped_frames += number - last - 1
            else:
                self.dropped_color_frames += number - last - 1
        self._last_number[stream] = number

    def _next_recorded(self):
        """The next recorded frame, or None at the recording's end."""
        rs = self._rs
        waited = 0.0
        while True:
            try:
                return self._frames.get(timeout=0.05)
            except queue.Empty:
                if self._player.current_status() == rs.playback_status.stopped and self._frames.empty():
                    return None
                waited += 0.05
                if waited > _STALL_S:
                    raise _voxfuse.IoError(f"{self._path}: the player delivered no frame for {_STALL_S:.0f} s")

    def _next_recorded_pair(self):
        """(depth, colour or None) from a recording, each depth frame with the colour frame nearest in time."""
        rs = self._rs
        while not self._ready:
            if self._ended:
                if not self._pending_depth:
                    return None
                self._ready = [(d, self._previous_color) for d in self._pending_depth]
                self._pending_depth = []
                break
            frame = self._next_recorded()
            if frame is None:
                self._ended = True
                continue
            is_depth = frame.get_profile().stream_type() == rs.stream.depth
            self._count_drops(frame, is_depth)
            if is_depth:
                if self._has_color:
                    self._pending_depth.append(frame)
                else:
                    self._ready.append((frame, None))
                continue
            # A colour frame decides the depth frames up to its time: each takes the nearer of it and the last.
            color, previous = frame, self._previous_color
            while self._pending_depth and self._pending_depth[0].get_timestamp() <= color.get_timestamp():
                depth = self._pending_depth.pop(0)
                t = depth.get_timestamp()
                if previous is not None and abs(previous.get_timestamp() - t) <= abs(color.get_timestamp() - t):
                    self._ready.append((depth, previous))
                else:
                    self._ready.append((depth, color))
            self._previous_color = color
        return self._ready.pop(0)

    def _next_live_pair(self):
        rs = self._rs
        try:
            frames = self._pipeline.wait_for_frames(int(self._timeout_s * 1000))
        except RuntimeError as e:
            raise _voxfuse.IoError(f"{self._description}: no frame within {self._timeout_s:g} s: {e}") from e
        depth, color = frames.get_depth_frame(), frames.get_color_frame()
        if not depth:
            raise _voxfuse.IoError(f"{self._description}: a frame set without depth")
        self._count_drops(depth, True)
        if color:
            self._count_drops(color, False)
        return (frames if self._aligner is not None else depth), (color or None)

    def _aligned(self, depth, color):
        """rs.align on a frame set made of the pair (recordings deliver the streams separately)."""
        rs = self._rs
        if not isinstance(depth, rs.composite_frame):
            if self._pairing is None:  # made once: a processing block that joins self._pair into a frame set
                self._paired = rs.frame_queue(1, keep_frames=True)
                self._pairing = rs.processing_block(
                    lambda f, src: src.frame_ready(src.allocate_composite_frame(list(self._pair)))
                )
                self._pairing.start(self._paired)
            self._pair = (depth, color)
            self._pairing.invoke(depth)
            depth = self._paired.wait_for_frame(1000)
            self._pair = None
        frames = self._aligner.process(depth.as_frameset())
        return frames.get_depth_frame(), frames.get_color_frame()

    def _to_frame(self, depth, color):
        if self._aligner is not None:
            if color is None:
                raise _voxfuse.IoError(f"{self._description}: a depth frame without colour cannot be aligned")
            depth, color = self._aligned(depth, color)
        elif isinstance(depth, self._rs.composite_frame):
            depth = depth.get_depth_frame()
        depth_array = np.asanyarray(depth.get_data())
        rgb = None
        if color is not None:
            rgb = np.asanyarray(color.get_data())
            if self._color_is_bgr:
                rgb = rgb[..., [2, 1, 0]]
        index = self._next_index
        self._next_index += 1
        return _voxfuse.Frame(
            depth_array, rgb, calib=self.calib, index=index, timestamp=depth.get_timestamp() / 1000.0
        )

    def __iter__(self):
        return self

    def __next__(self):
        if self._closed:
            raise StopIteration
        pair = self._next_live_pair() if self._live else self._next_recorded_pair()
        if pair is None:
            self.close()
            raise StopIteration
        return self._to_frame(*pair)

    # --- the rest of voxfuse.Source's interface --------------------------------------------------

    @property
    def description(self):
        return self._description

    @property
    def ground_truth(self):
        """Empty: a RealSense stream has no ground truth (as voxfuse.Source.ground_truth)."""
        return np.zeros((0,)), np.zeros((0, 4, 4))

    def close(self):
        """Stops the camera or the player; iterating afterwards yields nothing."""
        if self._closed:
            return
        self._closed = True
        if self._live:
            self._pipeline.stop()
            return
        self._stop.set()
        for sensor, _ in self._sensors:
            try:
                sensor.stop()
                sensor.close()
            except RuntimeError:
                pass  # already stopped at the recording's end

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    def __repr__(self):
        return f"<voxfuse.realsense.RealSenseSource {self._description}, align={self._align_mode}>"


def open_realsense(path, *, align="none", width=640, height=480, fps=30, timeout_s=5.0):
    """A RealSenseSource: a .bag/.db3 recording, or "realsense:" / "realsense:SERIAL" for a live camera.

    align: "none" (default), "color" or "depth" (see help(voxfuse.realsense)); width, height, fps: the
    live camera's stream mode; timeout_s: how long to wait for a live frame before voxfuse.IoError.
    """
    return RealSenseSource(path, align=align, width=width, height=height, fps=fps, timeout_s=timeout_s)


def write_recording(path, frames, calib, *, fps=30):
    """Records voxfuse.Frame objects (any source's) as a RealSense recording, through a librealsense
    software device: what RealSense input is tested with, no camera needed. Returns the frame count.

    calib is the frames' voxfuse.Calibration (an affine depth scale; its colour camera and
    T_depth_rgb become the recording's colour stream and extrinsics). Frame numbers and timestamps
    are the frames' own. librealsense 2.57 and later write ROS 2 bags (.db3), earlier ones .bag.
    """
    rs = _import_rs(path)
    depth_k, color_k = calib.depth, calib.rgb if calib.rgb.width > 0 else calib.depth
    device = rs.software_device()
    depth_sensor, color_sensor = device.add_sensor("Depth"), device.add_sensor("Color")

    def video_stream(kind, uid, k, bpp, fmt):
        intrinsics = rs.intrinsics()
        intrinsics.width, intrinsics.height = k.width, k.height
        intrinsics.fx, intrinsics.fy, intrinsics.ppx, intrinsics.ppy = k.fx, k.fy, k.cx, k.cy
        intrinsics.model, intrinsics.coeffs = rs.distortion.none, [0.0] * 5
        s = rs.video_stream()
        s.type, s.index, s.uid, s.width, s.height = kind, 0, uid, k.width, k.height
        s.fps, s.bpp, s.fmt, s.intrinsics = fps, bpp, fmt, intrinsics
        return s

    depth_profile = depth_sensor.add_video_stream(video_stream(rs.stream.depth, 0, depth_k, 2, rs.format.z16))
    color_profile = color_sensor.add_video_stream(video_stream(rs.stream.color, 1, color_k, 3, rs.format.rgb8))
    depth_sensor.add_read_only_option(rs.option.depth_units, float(calib.depth_scale))
    T_rgb_depth = np.linalg.inv(np.asarray(calib.T_depth_rgb, dtype=np.float64))
    extrinsics = rs.extrinsics()
    extrinsics.rotation = [float(v) for v in T_rgb_depth[:3, :3].T.ravel()]  # column-major
    extrinsics.translation = [float(v) for v in T_rgb_depth[:3, 3]]
    depth_profile.register_extrinsics_to(color_profile, extrinsics)
    try:
        recorder = rs.recorder(str(path), device)
    except RuntimeError as e:
        raise _voxfuse.ConfigError(f"{path}: librealsense {rs.__version__} cannot record there: {e}") from e
    depth_sensor.open(depth_profile)
    color_sensor.open(color_profile)
    sinks = rs.frame_queue(2), rs.frame_queue(2)
    depth_sensor.start(sinks[0])
    color_sensor.start(sinks[1])
    count = 0
    try:
        for frame in frames:
            stamp_ms = frame.timestamp * 1000.0
            images = [(depth_sensor, depth_profile, np.ascontiguousarray(frame.depth), 2)]
            if frame.rgb is not None:
                images.append((color_sensor, color_profile, np.ascontiguousarray(frame.rgb), 3))
            for sensor, profile, pixels, bpp in images:
                f = rs.software_video_frame()
                f.pixels, f.stride, f.bpp = pixels, pixels.shape[1] * bpp, bpp
                f.timestamp, f.domain, f.frame_number = stamp_ms, rs.timestamp_domain.hardware_clock, frame.index
                f.profile = profile.as_video_stream_profile()
                sensor.on_video_frame(f)
            count += 1
    finally:
        depth_sensor.stop()
        color_sensor.stop()
        depth_sensor.close()
        color_sensor.close()
        del recorder  # the file is complete once the recorder is gone
    return count
