"""Python's cost per frame over the C++ pipeline's: the wall time of Pipeline.process (checking and
copying the arrays, the call, the result) against the engine's own time for the frame.

    python python/benchmarks/overhead.py [SOURCE] [--frames N] [--voxel-size M]
"""
import argparse
import statistics
import time

import voxfuse

parser = argparse.ArgumentParser()
parser.add_argument("source", nargs="?", default="data/synthetic_room")
parser.add_argument("--frames", type=int, default=40)
parser.add_argument("--voxel-size", type=float, default=0.005)
parser.add_argument("--device", default="cpu")
args = parser.parse_args()

source = voxfuse.open_source(args.source)
frames = [f for f, _ in zip(source, range(args.frames))]  # decoded first: decoding is not the pipeline's
pipeline = voxfuse.Pipeline(source.calib, voxel_size=args.voxel_size, device=args.device)
wall_ms, engine_ms = [], []
for f in frames:
    depth, rgb = f.depth, f.rgb
    t = time.perf_counter()
    result = pipeline.process(depth, rgb)
    wall_ms.append(1000.0 * (time.perf_counter() - t))
    engine_ms.append(result.timings["total"])
overhead = [w - e for w, e in zip(wall_ms, engine_ms)]
print(f"{len(frames)} frames of {source.description}")
print(f"median per frame: Pipeline.process {statistics.median(wall_ms):.2f} ms, engine {statistics.median(engine_ms):.2f} ms, "
      f"Python's share {statistics.median(overhead):.3f} ms = {100 * statistics.median(overhead) / statistics.median(engine_ms):.2f}%")
