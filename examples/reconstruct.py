"""Reconstructs a recorded RGB-D sequence and writes its mesh.

    python examples/reconstruct.py [SOURCE] [mesh.ply]     (default: the bundled synthetic room)
"""
import sys

import voxfuse

source = voxfuse.open_source(sys.argv[1] if len(sys.argv) > 1 else "data/synthetic_room")
pipeline = voxfuse.Pipeline(source.calib, voxel_size=0.01)  # any `voxfuse --help` setting, by name
for frame in source:
    result = pipeline.process_frame(frame)  # or pipeline.process(depth_array, rgb_array)
    print(f"frame {frame.index}: {result.status}, {result.quality}, {result.timings['total']:.1f} ms", end="\r")
mesh = pipeline.extract_mesh()
mesh.save(sys.argv[2] if len(sys.argv) > 2 else "mesh.ply")
summary = pipeline.summary()
print(f"\n{len(mesh.vertices)} vertices, {len(mesh.faces)} triangles; {summary['frames_per_s']:.1f} frames/s; "
      f"{summary['frames_lost']} frames lost, {summary['relocalisations']} relocalised")
