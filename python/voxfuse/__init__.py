"""VoxFuse: real-time dense 3D reconstruction from RGB-D frames.

    import voxfuse
    source = voxfuse.open_source("data/synthetic_room")
    pipeline = voxfuse.Pipeline(source.calib)
    for frame in source:
        result = pipeline.process_frame(frame)      # or pipeline.process(depth, rgb)
    pipeline.extract_mesh().save("mesh.ply")

RealSense recordings (.bag, .db3) and cameras ("realsense:") open the same way, through pyrealsense2
(voxfuse.realsense); pipeline.log_to_rerun(result, frame) logs to Rerun (voxfuse.rerun_logging).
`python -m voxfuse SOURCE` reconstructs from the command line. Everything runs in the C++ library (on the GPU with device="cuda"); arrays going out view the
library's memory without a copy.
"""

from ._voxfuse import (
    ConfigError,
    DeviceError,
    Error,
    Frame,
    FrameResult,
    Calibration,
    Intrinsics,
    IoError,
    Mesh,
    ParseError,
    Pipeline,
    PointCloud,
    Settings,
    Source,
    built_with_cuda,
    cpu_threads,
    cuda_available,
    evaluate_trajectory,
    open_source as _open_native_source,
    read_tum_trajectory,
    set_cpu_threads,
    write_tum_trajectory,
)
from ._voxfuse import __version__  # the library's, from CMakeLists.txt project(VERSION)
from . import realsense as _realsense
from .rerun_logging import log_to_rerun as _log_to_rerun


def open_source(path, **options):
    """Opens a recording or a camera for its frames.

    RealSense (voxfuse.realsense, needs pyrealsense2): a .bag or .db3 recording, "realsense:" for the
    first camera, "realsense:SERIAL" for one; options align="none"|"color"|"depth", and for a camera
    width, height, fps, timeout_s. Anything else is what `voxfuse PATH` opens, as a voxfuse.Source (a TUM
    RGB-D folder, a per-frame folder, a Stray Scanner capture, an .oni file, PPM/PGM patterns), with the
    options of help(voxfuse._voxfuse.open_source): calib, rgb, depth, first_index, min_confidence, labels,
    threaded, skip_unreadable.
    """
    if _realsense.handles(path):
        return _realsense.open_realsense(path, **options)
    return _open_native_source(path, **options)


Pipeline.log_to_rerun = _log_to_rerun

__all__ = [
    "Calibration",
    "ConfigError",
    "DeviceError",
    "Error",
    "Frame",
    "FrameResult",
    "Intrinsics",
    "IoError",
    "Mesh",
    "ParseError",
    "Pipeline",
    "PointCloud",
    "Settings",
    "Source",
    "built_with_cuda",
    "cpu_threads",
    "cuda_available",
    "evaluate_trajectory",
    "open_source",
    "read_tum_trajectory",
    "set_cpu_threads",
    "write_tum_trajectory",
]
