#pragma once
// Marching cubes for one cell: the cube's topology, the case table and the per-cell and per-edge
// functions shared by the CPU loop and a CUDA kernel.
//
// The case table is not typed in: marching_cubes_detail::build() derives it at compile time from the
// cube topology. On each face, the cut edges are joined into segments that separate the inside
// corners; the segments of the six faces chain into closed loops around the cube, and each loop
// becomes a fan of triangles whose inner sides never lie in a face. The choice on a face depends on
// that face's four corners only, so the two cells that share a face cut it the same way: meshes are
// closed wherever all their cells are complete, and no edge has more than two triangles (the classic
// 256-case table resolves ambiguous faces per cube and leaves holes). Corner k sits at
// (k & 1, (k >> 1) & 1, (k >> 2) & 1), the order of the trilinear readers in shared/VoxelAccess.h.

#include <cstdint>

#include "voxfuse/core/Math.h"

namespace voxfuse {

// Edge e runs along axis e / 4, from the corner with that coordinate 0 to the one with it 1; bit 0 of
// e % 4 is the lower of the two other axes' coordinate, bit 1 the higher's.
constexpr int kCubeCorners = 8;
constexpr int kCubeEdges = 12;
// The most triangles one case produces (a case needing more would stop the compile-time generation).
constexpr int kMaxCellTriangles = 5;

VF_HOST_DEVICE constexpr Vec3i cubeCornerOffset(int corner) {
    return {corner & 1, (corner >> 1) & 1, (corner >> 2) & 1};
}
VF_HOST_DEVICE constexpr int cubeEdgeAxis(int edge) { return edge >> 2; }
// The corner where the edge starts (its axis coordinate is 0).
VF_HOST_DEVICE constexpr int cubeEdgeStartCorner(int edge) {
    const int axis = edge >> 2, u = edge & 1, v = (edge >> 1) & 1;
    // The two other axes in increasing order carry u and v.
    return axis == 0 ? (u << 1) | (v << 2) : axis == 1 ? u | (v << 2) : u | (v << 1);
}
VF_HOST_DEVICE constexpr int cubeEdgeEndCorner(int edge) {
    return cubeEdgeStartCorner(edge) | (1 << cubeEdgeAxis(edge));
}
// The edge joining two corners that differ in exactly one coordinate.
VF_HOST_DEVICE constexpr int cubeEdgeBetween(int corner_a, int corner_b) {
    const int axis = (corner_a ^ corner_b) == 1 ? 0 : (corner_a ^ corner_b) == 2 ? 1 : 2;
    const int start = corner_a & ~(1 << axis);
    const int u = axis == 0 ? (start >> 1) & 1 : start & 1;
    const int v = axis == 2 ? (start >> 1) & 1 : (start >> 2) & 1;
    return axis * 4 + u + 2 * v;
}

// Triangles of each of the 256 cases, as triples of cut edges. Vertices wind counter-clockwise seen
// from outside, i.e. (b - a) x (c - a) points towards positive SDF (free space).
struct MarchingCubesTable {
    std::int8_t triangle_edges[256][3 * kMaxCellTriangles];
    std::uint8_t triangle_count[256];
    std::uint16_t cut_edges[256];  // bit e set when edge e joins an inside and an outside corner
};

namespace marching_cubes_detail {

// The four corners of face `face` (axis face / 2, at coordinate face % 2), counter-clockwise seen from
// outside the cube: around +axis for the far face, around -axis for the near one.
constexpr void faceCorners(int face, int out[4]) {
    const int axis = face / 2, side = face % 2;
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;  // (u, v, axis) is right-handed
    const int ring[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int i = 0; i < 4; ++i) {
        const int k = side ? i : (4 - i) % 4;  // the near face is seen from the other side: reversed
        out[i] = (side << axis) | (ring[k][0] << u) | (ring[k][1] << v);
    }
}

constexpr bool edgeOnFace(int edge, int face) {
    const int axis = face / 2, side = face % 2;
    return cubeEdgeAxis(edge) != axis && ((cubeEdgeStartCorner(edge) >> axis) & 1) == side;
}

constexpr bool edgesShareAFace(int a, int b) {
    for (int face = 0; face < 6; ++face)
        if (edgeOnFace(a, face) && edgeOnFace(b, face)) return true;
    return false;
}

// Whether a fan over loop[0..n) from loop[apex] has an inner side between two edges of one face.
constexpr bool fanSidesLieOnAFace(const int* loop, int n, int apex) {
    for (int k = 2; k + 1 < n; ++k)
        if (edgesShareAFace(loop[apex], loop[(apex + k) % n])) return true;
    return false;
}

constexpr MarchingCubesTable build() {
    MarchingCubesTable table{};
    for (int cube = 0; cube < 256; ++cube) {
        auto inside = [cube](int corner) { return ((cube >> corner) & 1) != 0; };
        // next[e]: the cut edge that follows cut edge e along its loop. On a face, walking its corners
        // counter-clockwise, a segment runs from where the walk enters the inside (X) to where it
        // leaves it (Y), so that outside lies to its left seen from outside the cube. Each cut edge is
        // an X on one of its two faces and a Y on the other, so the segments chain into loops.
        int next[kCubeEdges] = {-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1};
        std::uint16_t cut = 0;
        for (int face = 0; face < 6; ++face) {
            int c[4] = {0, 0, 0, 0};
            faceCorners(face, c);
            // Each inside corner run c[i..j] gets the segment from the edge before it to the edge after
            // it; on a face with two diagonal inside corners that separates them (the face's rule).
            for (int i = 0; i < 4; ++i) {
                if (!inside(c[i]) || inside(c[(i + 3) % 4])) continue;  // c[i] starts an inside run
                int j = i;
                while (inside(c[(j + 1) % 4])) j = (j + 1) % 4;
                const int enter = cubeEdgeBetween(c[(i + 3) % 4], c[i]);
                const int leave = cubeEdgeBetween(c[j], c[(j + 1) % 4]);
                next[enter] = leave;
                cut |= std::uint16_t((1 << enter) | (1 << leave));
            }
        }
        table.cut_edges[cube] = cut;
        bool used[kCubeEdges] = {false, false, false, false, false, false, false, false, false, false, false, false};
        int count = 0;
        for (int first = 0; first < kCubeEdges; ++first) {
            if (next[first] < 0 || used[first]) continue;
            int loop[kCubeEdges] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
            int n = 0;
            for (int e = first; !used[e]; e = next[e]) {
                used[e] = true;
                loop[n++] = e;
            }
            // The loop becomes a fan. Its apex is chosen so that no inner side of the fan joins two
            // vertices on one cube face: such a side would lie in the face, where the neighbouring cell
            // may put a side too (an edge of four triangles, two sheets touching).
            int apex = 0;
            while (apex < n && fanSidesLieOnAFace(loop, n, apex)) ++apex;
            if (apex == n) apex = 0;  // never happens: the table test checks it
            for (int k = 1; k + 1 < n; ++k) {
                table.triangle_edges[cube][3 * count + 0] = std::int8_t(loop[apex]);
                table.triangle_edges[cube][3 * count + 1] = std::int8_t(loop[(apex + k) % n]);
                table.triangle_edges[cube][3 * count + 2] = std::int8_t(loop[(apex + k + 1) % n]);
                ++count;
            }
        }
        table.triangle_count[cube] = std::uint8_t(count);
    }
    return table;
}

}  // namespace marching_cubes_detail

// The table, derived at compile time: host code reads kMarchingCubesTable, device code a copy in
// constant memory; marchingCubesTable() picks the right one for either.
inline constexpr MarchingCubesTable kMarchingCubesTable = marching_cubes_detail::build();
#if defined(__CUDACC__)
static __constant__ MarchingCubesTable kMarchingCubesTableDevice = marching_cubes_detail::build();
#endif

VF_HOST_DEVICE inline const MarchingCubesTable& marchingCubesTable() {
#if defined(__CUDA_ARCH__)
    return kMarchingCubesTableDevice;
#else
    return kMarchingCubesTable;
#endif
}

// Corners are inside (the case bit is set) where the SDF is negative; zero counts as outside, as it
// does for the raycast's front-to-back crossing.
VF_HOST_DEVICE inline int cubeCase(const float sdf[kCubeCorners]) {
    int cube = 0;
    for (int k = 0; k < kCubeCorners; ++k) cube |= int(sdf[k] < 0.f) << k;
    return cube;
}

VF_HOST_DEVICE inline bool edgeIsCut(float sdf_start, float sdf_end) { return (sdf_start < 0.f) != (sdf_end < 0.f); }

// Where the linear interpolation of the SDF crosses zero on a cut edge, as a fraction of the edge from
// its start. Kept a thousandth of the edge away from the corners: a corner whose SDF is exactly zero
// would otherwise put the vertices of several edges at one point (duplicate positions, zero-area
// triangles); the shift is at most 1/1000 voxel.
VF_HOST_DEVICE inline float edgeCrossing(float sdf_start, float sdf_end) {
    const float t = sdf_start / (sdf_start - sdf_end);
    return clampValue(t, 1e-3f, 1.f - 1e-3f);
}

// One component of the SDF gradient at a grid point from its two neighbours along an axis: central
// difference where both were observed, one-sided where only one was, 0 where neither was.
VF_HOST_DEVICE inline float sdfDifference(float minus, bool minus_observed, float centre, float plus,
                                          bool plus_observed) {
    if (minus_observed && plus_observed) return 0.5f * (plus - minus);
    if (plus_observed) return plus - centre;
    if (minus_observed) return centre - minus;
    return 0.f;
}

VF_HOST_DEVICE inline Vec3f lerp(Vec3f a, Vec3f b, float t) { return a + (b - a) * t; }

}  // namespace voxfuse
