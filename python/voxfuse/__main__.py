"""python -m voxfuse SOURCE: reconstruct a recording or camera from the command line (also `voxfuse-py`).

The Python entry point reaches what only the Python package reads (RealSense recordings and cameras,
Rerun logging) and takes every recording `voxfuse` takes. It writes trajectory.txt (TUM format),
summary.json and, with --mesh, mesh.ply into --out. Exit status as voxfuse's: 0 done, 2 refused
(the error says why), 3 an unexpected error, 4 ran but fused nothing into the map.
"""

import argparse
import json
import os
import pathlib
import sys
import tempfile

from . import Error, Pipeline, Settings, evaluate_trajectory, open_source, write_tum_trajectory
from . import realsense

EXIT_REFUSED, EXIT_UNEXPECTED, EXIT_NOTHING_FUSED = 2, 3, 4
OUTPUTS = ("trajectory.txt", "summary.json", "mesh.ply")
BUNDLED_ROOM = pathlib.Path(__file__).resolve().parents[2] / "data" / "synthetic_room"  # in a checkout


def _setting(text):
    """NAME=VALUE, VALUE converted to the setting's type (voxfuse.Settings.table())."""
    name, sep, value = text.partition("=")
    if not sep or not name:
        raise argparse.ArgumentTypeError(f"--set takes NAME=VALUE, not {text!r}")
    rows = {row["name"]: row for row in Settings.table()}
    if name not in rows:
        raise argparse.ArgumentTypeError(f"unknown setting {name!r}; the settings: {', '.join(sorted(rows))}")
    kind, default = rows[name]["type"], rows[name]["default"]
    try:
        if kind == "bool":
            if value.lower() not in ("true", "false", "1", "0", "on", "off"):
                raise ValueError(value)
            return name, value.lower() in ("true", "1", "on")
        convert = int if kind.endswith("int") else float if kind.endswith("float") else str
        if kind.startswith("list"):
            return name, [convert(v) for v in value.replace(",", " ").split()]
        return name, convert(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"setting {name} takes a {kind} (default {default!r}), not {value!r}") from None


def _parser():
    p = argparse.ArgumentParser(
        prog="python -m voxfuse",
        description="Track and fuse an RGB-D recording or camera into a TSDF map (see `voxfuse --help` for the C++ "
        "command line).",
    )
    p.add_argument(
        "source",
        nargs="?",
        default=str(BUNDLED_ROOM),
        help="a RealSense .bag/.db3 recording, realsense:[SERIAL] for a camera, or any recording voxfuse opens "
        "(default: the bundled synthetic room, from a checkout)",
    )
    p.add_argument("--out", default="voxfuse_out", help="output folder (default voxfuse_out)")
    p.add_argument("--overwrite", action="store_true", help="replace an earlier run's outputs in --out")
    p.add_argument("--frames", type=int, default=-1, help="process at most this many frames (default all)")
    p.add_argument("--mesh", action="store_true", help="write mesh.ply")
    p.add_argument("--align", choices=realsense.ALIGN_MODES, default="none", help="RealSense: depth and colour")
    p.add_argument("--rerun", metavar="FILE.rrd|spawn", help="log to Rerun: save to an .rrd file, or spawn the viewer")
    p.add_argument("--rerun-mesh-every", type=int, default=30, metavar="N", help="log the mesh every N frames")
    p.add_argument("--set", type=_setting, action="append", default=[], metavar="NAME=VALUE",
                   help="a pipeline setting (voxfuse.Settings: the names of `voxfuse --help`), e.g. voxel_size=0.01")
    return p


def _write_atomically(path, text):
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(path), prefix=".tmp-")
    umask = os.umask(0)
    os.umask(umask)
    try:
        os.chmod(tmp, 0o666 & ~umask)  # as open() would make it, not mkstemp's 0600
        with os.fdopen(fd, "w") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def _start_rerun(target):
    from .rerun_logging import _import_rerun, blueprint

    rr = _import_rerun()
    recording = rr.RecordingStream("voxfuse")
    if target == "spawn":
        recording.spawn()
    elif target.endswith(".rrd"):
        recording.save(target)
    else:
        raise Error(f"--rerun takes a file ending .rrd or 'spawn', not {target!r}")
    recording.send_blueprint(blueprint())
    return recording


def run(args):
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    existing = [name for name in OUTPUTS if (out / name).exists()]
    if existing and not args.overwrite:
        raise Error(f"{out}: holds an earlier run's {', '.join(existing)}; give --overwrite to replace them")
    options = {"align": args.align} if realsense.handles(args.source) else {}
    source = open_source(args.source, **options)
    try:
        return _reconstruct(args, out, source)
    finally:
        if hasattr(source, "close"):
            source.close()  # a camera or a RealSense player stops now, not at exit


def _reconstruct(args, out, source):
    pipeline = Pipeline(source.calib, **dict(args.set))
    recording = _start_rerun(args.rerun) if args.rerun else None
    fused = 0
    for frame in source:
        if 0 <= args.frames <= pipeline.frames_processed:
            break
        result = pipeline.process_frame(frame)
        fused += result.fused
        if recording is not None:
            pipeline.log_to_rerun(result, frame, recording=recording, mesh_every=args.rerun_mesh_every)
        print(f"frame {frame.index}: {result.status}, {result.quality}, {result.timings['total']:.1f} ms",
              end="\r", file=sys.stderr)
    print(file=sys.stderr)
    timestamps, poses = pipeline.trajectory
    write_tum_trajectory(str(out / "trajectory.txt"), timestamps, poses)
    summary = pipeline.summary()
    summary["source"] = source.description
    for name in ("dropped_frames", "dropped_color_frames", "unreadable_frames"):
        if hasattr(source, name):
            summary[name] = getattr(source, name)
    gt_timestamps, gt_poses = source.ground_truth
    if len(gt_timestamps) and len(timestamps):
        summary["trajectory_error"] = evaluate_trajectory(timestamps, poses, gt_timestamps, gt_poses)
    if args.mesh:
        pipeline.extract_mesh().save(str(out / "mesh.ply"))
    if recording is not None:
        from .rerun_logging import log_mesh

        log_mesh(pipeline, recording=recording)
        recording.flush()
    _write_atomically(str(out / "summary.json"), json.dumps(summary, indent=2, default=str) + "\n")
    print(f"voxfuse: {pipeline.frames_processed} frames, {fused} fused -> {out}", file=sys.stderr)
    if fused == 0 and args.frames != 0:
        print("voxfuse: no frame could be fused into the map", file=sys.stderr)
        return EXIT_NOTHING_FUSED
    return 0


def main(argv=None):
    parser = _parser()
    args = parser.parse_args(argv)
    if args.source == str(BUNDLED_ROOM) and not BUNDLED_ROOM.exists():
        parser.error("give a SOURCE (the bundled synthetic room is only in a checkout)")
    try:
        return run(args)
    except (Error, ImportError, OSError) as e:
        print(f"voxfuse: {e}", file=sys.stderr)
        return EXIT_REFUSED
    except KeyboardInterrupt:
        return 130
    except Exception as e:  # noqa: BLE001 - said, with the status scripts can tell apart
        print(f"voxfuse: unexpected error: {type(e).__name__}: {e}", file=sys.stderr)
        return EXIT_UNEXPECTED


if __name__ == "__main__":
    sys.exit(main())
