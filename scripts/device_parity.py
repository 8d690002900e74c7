#!/usr/bin/env python3
"""CPU-GPU parity of two voxfuse_bench runs on the same frames (scripts/gpu_check.sh runs both on the
carried teddy depth pack): per-frame poses, ATE, and the meshes. Standard library only (the GPU
machine has python3 but no packages).

    scripts/device_parity.py CPU_PREFIX GPU_PREFIX
    scripts/device_parity.py --sample-mesh MESH.ply SAMPLE.ply    (what gpu_bundle.sh carries)

reads PREFIX.json (--json), PREFIX_trajectory.txt (--trajectory) and the meshes: PREFIX_mesh.ply
(--mesh-out) of both runs, or, where the CPU run's mesh was too large to carry, CPU_PREFIX_mesh_sample.ply
(a sample of its vertices, --sample-mesh) against the GPU run's whole mesh. The runs are tracked
independently, so the GPU's rounding of the tracker's sums may move the poses: tolerances, not bit
equality (the engine tests compare bit for bit at given poses). Poses within 1 mm and 0.1 degree frame
by frame, ATE within 0.5 mm, triangle counts within 0.5%, 99% of the sampled vertices within 0.1 mm of
the other mesh's nearest vertex. Prints one line per measure and a verdict; exits 1 when a tolerance
is missed, 2 when an input is missing."""
import json
import math
import os
import struct
import sys


def load_trajectory(path):
    poses = {}
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            v = [float(x) for x in line.split()]
            poses[round(v[0], 6)] = (v[1:4], v[4:8])
    return poses


def rotation_between_deg(qa, qb):
    """Angle of the rotation between two unit quaternions (x, y, z, w): of conj(qa) * qb, through
    atan2, which stays exact for small angles (acos of a dot product near 1 does not)."""
    ax, ay, az, aw = -qa[0], -qa[1], -qa[2], qa[3]
    bx, by, bz, bw = qb
    x = aw * bx + ax * bw + ay * bz - az * by
    y = aw * by - ax * bz + ay * bw + az * bx
    z = aw * bz + ax * by - ay * bx + az * bw
    w = aw * bw - ax * bx - ay * by - az * bz
    return math.degrees(2.0 * math.atan2(math.sqrt(x * x + y * y + z * z), abs(w)))


def ply_vertices(path):
    """x, y, z of a binary little-endian PLY's vertices (as io/MeshIO.cpp writes them)."""
    sizes = {"float": 4, "uchar": 1, "ushort": 2, "int": 4, "uint": 4, "double": 8, "short": 2, "char": 1}
    with open(path, "rb") as f:
        count, props, in_vertex = 0, [], False
        while True:
            line = f.readline().decode("ascii", "replace").strip()
            if not line:
                raise ValueError(f"{path}: the header does not end")
            words = line.split()
            if words[0] == "format" and words[1] != "binary_little_endian":
                raise ValueError(f"{path}: {words[1]} PLY, expected binary_little_endian")
            if words[0] == "element":
                in_vertex = words[1] == "vertex"
                if in_vertex:
                    count = int(words[2])
            elif words[0] == "property" and in_vertex:
                props.append((words[2], sizes[words[1]]))
            elif words[0] == "end_header":
                break
        stride = sum(size for _, size in props)
        names = [name for name, _ in props]
        if names[:3] != ["x", "y", "z"]:
            raise ValueError(f"{path}: vertex properties start {names[:3]}, expected x y z")
        data = f.read(stride * count)
        if len(data) < stride * count:
            raise ValueError(f"{path}: truncated vertex data")
    return [struct.unpack_from("<3f", data, i * stride) for i in range(count)]


def nearest_distances(reference, queries, cell):
    """Distance from each query to its nearest reference point, searched within one cell around it
    (farther ones count as `cell`)."""
    grid = {}
    for p in reference:
        grid.setdefault((int(p[0] // cell), int(p[1] // cell), int(p[2] // cell)), []).append(p)
    out = []
    for q in queries:
        c = (int(q[0] // cell), int(q[1] // cell), int(q[2] // cell))
        best = cell * cell
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dz in (-1, 0, 1):
                    for p in grid.get((c[0] + dx, c[1] + dy, c[2] + dz), ()):
                        d = (p[0] - q[0]) ** 2 + (p[1] - q[1]) ** 2 + (p[2] - q[2]) ** 2
                        if d < best:
                            best = d
        out.append(math.sqrt(best))
    return out


def write_vertex_ply(path, vertices):
    with open(path, "wb") as f:
        f.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(vertices)}\n"
                 "property float x\nproperty float y\nproperty float z\nend_header\n").encode("ascii"))
        f.write(b"".join(struct.pack("<3f", *v) for v in vertices))


def sample_mesh(mesh_path, sample_path, count=100000):
    vertices = ply_vertices(mesh_path)
    step = max(1, len(vertices) // count)
    write_vertex_ply(sample_path, vertices[::step])
    print(f"{sample_path}: {len(vertices[::step])} of {len(vertices)} vertices (every {step})")


def compare_vertices(reference, queries, what, failures):
    dist = sorted(nearest_distances(reference, queries, 0.001))
    within = sum(d <= 1e-4 for d in dist) / max(1, len(dist))
    p99 = dist[int(0.99 * (len(dist) - 1))] if dist else 0.0
    print(f"mesh: of {len(dist)} {what} sampled, {100.0 * within:.2f}% lie within 0.1 mm of the other mesh's nearest vertex "
          f"(99th percentile {1000.0 * p99:.3f} mm)")
    if within < 0.99:
        failures.append(f"fewer than 99% of the {what} within 0.1 mm of the other mesh")


def main():
    if len(sys.argv) == 4 and sys.argv[1] == "--sample-mesh":
        sample_mesh(sys.argv[2], sys.argv[3])
        return
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    cpu, gpu = sys.argv[1], sys.argv[2]
    needed = [p + s for p in (cpu, gpu) for s in (".json", "_trajectory.txt")]
    missing = [p for p in needed if not os.path.exists(p)]
    if missing:
        print("device parity: missing " + ", ".join(missing))
        sys.exit(2)
    failures = []

    a, b = load_trajectory(cpu + "_trajectory.txt"), load_trajectory(gpu + "_trajectory.txt")
    common = sorted(set(a) & set(b))
    worst_mm = worst_deg = 0.0
    worst_frame = 0
    for i, t in enumerate(common):
        d_mm = 1000.0 * math.dist(a[t][0], b[t][0])
        d_deg = rotation_between_deg(a[t][1], b[t][1])
        if d_mm > worst_mm:
            worst_mm, worst_frame = d_mm, i
        worst_deg = max(worst_deg, d_deg)
    print(f"poses: {len(common)} frames in both ({len(a)} cpu, {len(b)} gpu); largest difference {worst_mm:.3f} mm "
          f"(frame {worst_frame}) and {worst_deg:.4f} degrees")
    if len(common) != len(a) or len(common) != len(b):
        failures.append("the runs kept different frames")
    if worst_mm > 1.0 or worst_deg > 0.1:
        failures.append("poses differ by more than 1 mm / 0.1 degree")

    ja, jb = json.load(open(cpu + ".json")), json.load(open(gpu + ".json"))
    if "ate_rmse_m" in ja and "ate_rmse_m" in jb:
        ate_a, ate_b = 1000.0 * ja["ate_rmse_m"], 1000.0 * jb["ate_rmse_m"]
        print(f"ATE: cpu {ate_a:.2f} mm, gpu {ate_b:.2f} mm")
        if abs(ate_a - ate_b) > 0.5:
            failures.append("ATE differs by more than 0.5 mm")
    else:
        print("ATE: no ground truth in the runs")
    for key in ("tracking_failed_frames", "frames_lost"):
        if ja.get(key) != jb.get(key):
            failures.append(f"{key}: cpu {ja.get(key)}, gpu {jb.get(key)}")

    ta, tb = ja.get("meshing", {}).get("triangles"), jb.get("meshing", {}).get("triangles")
    if ta is not None and tb is not None:
        print(f"mesh: triangles cpu {ta}, gpu {tb}")
        if abs(tb - ta) > 0.005 * ta:
            failures.append("triangle counts differ by more than 0.5%")
    if os.path.exists(cpu + "_mesh.ply") and os.path.exists(gpu + "_mesh.ply"):
        va, vb = ply_vertices(cpu + "_mesh.ply"), ply_vertices(gpu + "_mesh.ply")
        compare_vertices(va, vb[::max(1, len(vb) // 100000)], "gpu vertices", failures)
    elif os.path.exists(cpu + "_mesh_sample.ply") and os.path.exists(gpu + "_mesh.ply"):
        compare_vertices(ply_vertices(gpu + "_mesh.ply"), ply_vertices(cpu + "_mesh_sample.ply"), "cpu vertices", failures)
    else:
        print("mesh: no meshes to compare")
    print("device parity: " + ("PASS" if not failures else "FAIL: " + "; ".join(failures)))
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
