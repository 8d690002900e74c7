"""VoxFuse: real-time dense 3D reconstruction from RGB-D frames.

    import voxfuse
    source = voxfuse.open_source("data/synthetic_room")
    pipeline = voxfuse.Pipeline(source.calib)
    for frame in source:
        result = pipeline.process_frame(frame)      # or pipeline.process(depth, rgb)
    pipeline.extract_mesh().save("mesh.ply")

Everything runs in the C++ library (on the GPU with device="cuda"); arrays going out view the
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
    open_source,
    read_tum_trajectory,
    set_cpu_threads,
    write_tum_trajectory,
)
from ._voxfuse import __version__  # the library's, from CMakeLists.txt project(VERSION)

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
