"""Logging a reconstruction to Rerun (https://rerun.io), through rerun-sdk (optional).

    import rerun as rr
    rr.init("voxfuse"); rr.save("run.rrd")             # or rr.spawn() for the viewer
    for frame in source:
        result = pipeline.process_frame(frame)
        pipeline.log_to_rerun(result, frame)            # or depth=..., rgb=... after Pipeline.process

Per frame: the camera pose and frustum, the depth and colour images, the model's raycast, tracking
quality and stage timings as scalars; every ``mesh_every`` frames the mesh. The world is VoxFuse's:
the first camera's frame, x right, y down, z forward, metres. Entities:

    world/camera                  camera-to-world pose (Transform3D)
    world/camera/image            the depth camera (Pinhole: its frustum) with depth, rgb and raycast
    world/camera/colour           the colour camera, where it is not the depth camera
    world/mesh                    the map's surface (Mesh3D)
    world/trajectory              the camera path so far, logged with each mesh (LineStrips3D)
    tracking/<name>, timings/<stage>   scalars (timings in ms)

``blueprint()`` lays these out (the world in 3D beside the camera's images and the plots);
``python -m voxfuse --rerun`` sends it, a script can with ``recording.send_blueprint(blueprint())``.
"""

import numpy as np

_QUALITY = {"failed": 0.0, "poor": 1.0, "good": 2.0}


def _import_rerun():
    try:
        import rerun as rr  # optional: only Rerun logging needs it
    except ImportError as e:
        raise ImportError("Rerun logging needs rerun-sdk: pip install rerun-sdk") from e
    return rr


def _pinhole(rr, k):
    """A camera's frustum: its intrinsics, x right, y down, z forward."""
    K = np.array([[k.fx, 0.0, k.cx], [0.0, k.fy, k.cy], [0.0, 0.0, 1.0]])
    return rr.Pinhole(image_from_camera=K, resolution=[k.width, k.height], camera_xyz=rr.ViewCoordinates.RDF)


def _transform(rr, T):
    """A 4x4 rigid transform (child to parent) as Rerun's."""
    T = np.asarray(T)
    return rr.Transform3D(translation=T[:3, 3], mat3x3=T[:3, :3])


def _same_camera(a, b):
    return (a.width, a.height, a.fx, a.fy, a.cx, a.cy) == (b.width, b.height, b.fx, b.fy, b.cx, b.cy)


def log_to_rerun(
    pipeline,
    result,
    frame=None,
    *,
    depth=None,
    rgb=None,
    recording=None,
    mesh_every=30,
    raycast="shaded",
    jpeg_quality=90,
):
    """Logs one processed frame to Rerun (see help(voxfuse.rerun_logging) for what and where).

    result: what Pipeline.process or process_frame returned for the frame; frame: the voxfuse.Frame
    (or give depth= and rgb= arrays, as passed to Pipeline.process); recording: a rerun.RecordingStream
    (default: rerun's global one, as rr.init made it); mesh_every: log the mesh on every frame whose
    index is a multiple of it (0: never); raycast: the render mode of the logged raycast (None: none);
    jpeg_quality: colour and raycast images are logged as JPEG of this quality (None: raw pixels, about
    2.4 MB a VGA frame with the depth). Depth is always logged as it is.
    """
    rr = _import_rerun()
    if not isinstance(mesh_every, int) or mesh_every < 0:
        raise ValueError(f"mesh_every must be a non-negative integer, not {mesh_every!r}")
    if frame is not None:
        depth = frame.depth if depth is None else depth
        rgb = frame.rgb if rgb is None else rgb
    calib = pipeline.calib

    def log(path, entity, static=False):
        rr.log(path, entity, static=static, recording=recording)

    def image(pixels):
        pixels = rr.Image(np.ascontiguousarray(np.asarray(pixels)[..., :3]))
        return pixels if jpeg_quality is None else pixels.compress(jpeg_quality=jpeg_quality)

    rr.set_time("frame", sequence=int(result.index), recording=recording)
    rr.set_time("time", duration=float(result.timestamp), recording=recording)
    log("world", rr.ViewCoordinates.RDF, static=True)
    if result.status != "lost":  # a lost frame has no pose of its own
        log("world/camera", _transform(rr, result.pose))
    log("world/camera/image", _pinhole(rr, calib.depth), static=True)
    if depth is not None:
        depth = np.asarray(depth)
        meter = 1.0 / calib.depth_scale if depth.dtype == np.uint16 else 1.0
        log("world/camera/image/depth", rr.DepthImage(depth, meter=meter))
    if rgb is not None:
        if calib.rgb.width <= 0 or _same_camera(calib.rgb, calib.depth):
            log("world/camera/image/rgb", image(rgb))
        else:
            log("world/camera/colour", _transform(rr, calib.T_depth_rgb), static=True)
            log("world/camera/colour", _pinhole(rr, calib.rgb), static=True)
            log("world/camera/colour/rgb", image(rgb))
    if raycast:
        log("world/camera/image/raycast", image(pipeline.render(raycast)))
    for name in ("inlier_ratio", "residual", "condition", "translation_constraint"):
        log(f"tracking/{name}", rr.Scalars(float(getattr(result, name))))
    log("tracking/quality", rr.Scalars(_QUALITY.get(result.quality, 0.0)))
    for stage, ms in result.timings.items():
        log(f"timings/{stage}", rr.Scalars(float(ms)))
    if mesh_every and result.index % mesh_every == 0:
        log_mesh(pipeline, recording=recording)


def blueprint():
    """The viewer layout for what log_to_rerun logs: the world (mesh, path, camera) in 3D, beside the
    depth camera's colour, depth and raycast, and the tracking and timing plots below (a colour camera
    apart from the depth camera is shown in the 3D view). The time panel follows the newest frame."""
    _import_rerun()
    import rerun.blueprint as rrb

    camera = "world/camera/image"
    return rrb.Blueprint(
        rrb.Vertical(
            rrb.Horizontal(
                # the depth would also show there as points, the raycast as a second image in the frustum
                rrb.Spatial3DView(
                    origin="world", contents=["+ /world/**", f"- /{camera}/depth", f"- /{camera}/raycast"], name="map"
                ),
                rrb.Vertical(
                    rrb.Spatial2DView(origin=camera, contents=f"{camera}/rgb", name="colour"),
                    rrb.Spatial2DView(origin=camera, contents=f"{camera}/depth", name="depth"),
                    rrb.Spatial2DView(origin=camera, contents=f"{camera}/raycast", name="raycast"),
                ),
                column_shares=[3, 1],
            ),
            rrb.Horizontal(
                rrb.TimeSeriesView(origin="tracking", name="tracking"),
                rrb.TimeSeriesView(origin="timings", name="stage ms"),
            ),
            row_shares=[3, 1],
        ),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed", timeline="frame", play_state="following"),
    )


def log_mesh(pipeline, *, recording=None, path="world/mesh"):
    """Logs the pipeline's mesh (marching cubes over the whole map) at `path`."""
    rr = _import_rerun()
    mesh = pipeline.extract_mesh()
    if len(mesh.faces) == 0:
        return
    colors = mesh.colors if mesh.colors is not None and len(mesh.colors) else None
    rr.log(
        path,
        rr.Mesh3D(
            vertex_positions=mesh.vertices,
            triangle_indices=mesh.faces,
            vertex_normals=mesh.normals if mesh.normals is not None and len(mesh.normals) else None,
            vertex_colors=colors,
        ),
        recording=recording,
    )
    _, poses = pipeline.trajectory
    if len(poses) > 1:
        rr.log("world/trajectory", rr.LineStrips3D([np.asarray(poses)[:, :3, 3]]), recording=recording)
