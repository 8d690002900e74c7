#pragma once
// The meshing engine's loop bodies (engines/MeshingEngine.h says what the output is): one team per
// meshed block (core/Team.h: a CUDA thread block, or one CPU thread), in two passes with a scan between.
//
// A vertex lies on a voxel edge and belongs to the block holding the edge's start voxel, which makes it
// exactly once however many cells and blocks use it. Within a block, vertices are ordered by edge
// (rows of voxels along x, z then y outermost; x, then the edge's axis, within a row) and triangles by
// cell; blocks follow the block list. The order depends on the scene only.
// - FindRowSigns (shared/MeshBlocks.h) keeps the signs of every block as bit masks per row of voxels.
// - CountBlockSurface gathers the signs of the block's neighbourhood, finds which edges of each row
//   carry a vertex (a bit mask per row, kept), and counts vertices and triangles per row and block.
// - Exclusive scans over the blocks place each block's output.
// - EmitBlockSurface unpacks the voxels again, writes each vertex at its place, and each triangle
//   corner as the output index of its edge's vertex: the owning block's first vertex, plus the
//   vertices of the rows before the edge's row, plus the set bits before the edge in its row's mask.
// Memory besides the output: about 130 bytes per block, and 640 per block with surface.

#include <cstdint>

#include "voxfuse/core/Atomics.h"
#include "voxfuse/core/Math.h"
#include "voxfuse/core/Team.h"
#include "voxfuse/objects/ClassLabel.h"
#include "voxfuse/objects/HashTableTypes.h"
#include "voxfuse/shared/MarchingCubes.h"
#include "voxfuse/shared/MeshBlocks.h"

namespace voxfuse::meshing {

// ---- One block's neighbourhood, unpacked ----

// Local coordinates -1 .. 9 per axis: the block's cells reach +1, the cells around its edges reach -1,
// and the gradients at its edges' far ends reach +2.
constexpr int kMarginBelow = 1, kMarginAbove = 2;
constexpr int kLocalSide = kBlockSide + kMarginBelow + kMarginAbove;
constexpr int kLocalCount = kLocalSide * kLocalSide * kLocalSide;
constexpr int kLocalRows = kLocalSide * kLocalSide;
// Rows of cells whose first corner is at y, z = -1 .. 7.
constexpr int kCellRowSide = kBlockSide + 1;
constexpr int kCellRows = kCellRowSide * kCellRowSide;
// The block's own rows of voxels (y, z = 0 .. 7).
constexpr int kBlockRows = kBlockSide * kBlockSide;
// Bit x + 1 of a row mask stands for x = -1 .. 9; bits 1 .. 8 are x = 0 .. 7, the block's own.
constexpr unsigned kBlockBits = 0x1FE;

VF_HOST_DEVICE constexpr int localStride(int axis) { return axis == 0 ? 1 : axis == 1 ? kLocalSide : kLocalRows; }
VF_HOST_DEVICE constexpr int localIndex(Vec3i l) {
    return (l.x + kMarginBelow) + kLocalSide * ((l.y + kMarginBelow) + kLocalSide * (l.z + kMarginBelow));
}
VF_HOST_DEVICE constexpr int rowIndex(int y, int z) { return (y + kMarginBelow) + kLocalSide * (z + kMarginBelow); }
VF_HOST_DEVICE constexpr int cellRowIndex(int y, int z) { return (y + 1) + kCellRowSide * (z + 1); }
VF_HOST_DEVICE constexpr int cornerStep(int corner) {
    return (corner & 1) * localStride(0) + ((corner >> 1) & 1) * localStride(1) + ((corner >> 2) & 1) * localStride(2);
}

VF_HOST_DEVICE inline int lowestBit(unsigned mask) {  // mask != 0
#if defined(__CUDA_ARCH__)
    return __ffs(int(mask)) - 1;
#else
    return __builtin_ctz(mask);
#endif
}
VF_HOST_DEVICE inline int bitCount(unsigned mask) {
#if defined(__CUDA_ARCH__)
    return __popc(mask);
#else
    return __builtin_popcount(mask);
#endif
}

// The signs of a block's neighbourhood as bit masks per row along x: whole rows of cells and edges are
// tested at once, and only the few on the surface are visited one by one.
struct BlockSigns {
    int neighbours[27];                           // list places of the blocks at offsets -1 .. 1 (x fastest), -1: none
    std::uint16_t observed_rows[kLocalRows];      // weight > 0
    std::uint16_t negative_rows[kLocalRows];      // observed and SDF < 0
    std::uint16_t complete_cell_rows[kCellRows];  // all eight corners observed
    std::uint16_t surface_cell_rows[kCellRows];   // complete, with both signs
};

// The voxels of a block's neighbourhood as the vertices need them.
template <class TVoxel>
struct BlockVoxels {
    float sdf[kLocalCount];  // 1 where unobserved
    bool observed[kLocalCount];
    Vec3u8 color[TVoxel::hasColor ? kLocalCount : 1];
    bool colored[TVoxel::hasColor ? kLocalCount : 1];
    ClassId label[TVoxel::hasLabel ? kLocalCount : 1];  // kNoLabel where unobserved or without a class (w_label == 0)

    VF_HOST_DEVICE Vec3f gradient(int i) const {
        Vec3f g;
        for (int a = 0; a < 3; ++a) {
            const int s = localStride(a);
            g[a] = sdfDifference(sdf[i - s], observed[i - s], sdf[i], sdf[i + s], observed[i + s]);
        }
        return g;
    }
};

// Row (y, z) of the neighbourhood, y and z in -1 .. 9: its voxels and sign masks. s.neighbours must be set.
template <class TVoxel, class TBlocks>
VF_HOST_DEVICE void unpackRow(const TBlocks& blocks, Vec3i block, int y, int z, BlockSigns& s,
                              BlockVoxels<TVoxel>& voxels) {
    // (c + 8) >> 3 is 0, 1 or 2 for c = -1 .. 9: the neighbour below, this block, the one above.
    const int ny = (y + 8) >> 3, nz = (z + 8) >> 3;
    unsigned observed_bits = 0, negative_bits = 0;
    int i = localIndex({-kMarginBelow, y, z});
    for (int x = -kMarginBelow; x < kBlockSide + kMarginAbove; ++x, ++i) {
        const int nx = (x + 8) >> 3;
        const int n = s.neighbours[nx + 3 * ny + 9 * nz];
        const TVoxel* v =
            n >= 0 ? blocks.voxel(block + Vec3i{nx - 1, ny - 1, nz - 1}, n, Vec3i{x & 7, y & 7, z & 7}) : nullptr;
        const bool observed = v && v->w_depth > 0;
        const float sdf = observed ? TVoxel::sdfToFloat(v->sdf) : 1.f;
        observed_bits |= unsigned(observed) << (x + 1);
        negative_bits |= unsigned(observed && sdf < 0.f) << (x + 1);
        voxels.observed[i] = observed;
        voxels.sdf[i] = sdf;
        if constexpr (TVoxel::hasColor) {
            voxels.colored[i] = observed && v->w_color > 0;
            voxels.color[i] = voxels.colored[i] ? v->clr : Vec3u8{0, 0, 0};
        }
        if constexpr (TVoxel::hasLabel) voxels.label[i] = observed && v->w_label > 0 ? v->label : kNoLabel;
    }
    s.observed_rows[rowIndex(y, z)] = std::uint16_t(observed_bits);
    s.negative_rows[rowIndex(y, z)] = std::uint16_t(negative_bits);
}

// Row (y, z) of the neighbourhood's sign masks, y and z in -1 .. 8 and x = -1 .. 8 (what cells and edges
// read), from the blocks' row signs: bit 7 of the neighbour below, the block's own eight bits, bit 0 of
// the neighbour above. s.neighbours must be set.
VF_HOST_DEVICE inline void gatherSignRow(const RowSigns* row_signs, int y, int z, BlockSigns& s) {
    const int ny = (y + 8) >> 3, nz = (z + 8) >> 3;
    const int r = (y & 7) + kBlockSide * (z & 7);
    unsigned observed = 0, negative = 0;
    for (int nx = 0; nx < 3; ++nx) {
        const int n = s.neighbours[nx + 3 * ny + 9 * nz];
        if (n < 0) continue;
        const RowSigns rs = row_signs[n * kRowsPerBlock + r];
        const unsigned keep = nx == 0 ? 0x80u : nx == 1 ? 0xFFu : 0x01u;
        const int shift = nx == 0 ? -7 : nx == 1 ? 1 : 9;  // to bit x + 1
        const unsigned o = rs.observed & keep, g = rs.negative & keep;
        observed |= shift < 0 ? o >> -shift : o << shift;
        negative |= shift < 0 ? g >> -shift : g << shift;
    }
    s.observed_rows[rowIndex(y, z)] = std::uint16_t(observed);
    s.negative_rows[rowIndex(y, z)] = std::uint16_t(negative);
}

// Cells of row (y, z), y and z in -1 .. 7: a cell at x uses voxels x and x + 1 of four rows, so its
// bit x + 1 is that of A & (A >> 1).
VF_HOST_DEVICE inline void classifyCellRow(int y, int z, BlockSigns& s) {
    const int r[4] = {rowIndex(y, z), rowIndex(y + 1, z), rowIndex(y, z + 1), rowIndex(y + 1, z + 1)};
    const unsigned all_observed =
        s.observed_rows[r[0]] & s.observed_rows[r[1]] & s.observed_rows[r[2]] & s.observed_rows[r[3]];
    const unsigned any_negative =
        s.negative_rows[r[0]] | s.negative_rows[r[1]] | s.negative_rows[r[2]] | s.negative_rows[r[3]];
    const unsigned all_negative =
        s.negative_rows[r[0]] & s.negative_rows[r[1]] & s.negative_rows[r[2]] & s.negative_rows[r[3]];
    const unsigned complete = all_observed & (all_observed >> 1) & 0x1FFu;
    const unsigned mixed = (any_negative | (any_negative >> 1)) & ~(all_negative & (all_negative >> 1));
    s.complete_cell_rows[cellRowIndex(y, z)] = std::uint16_t(complete);
    s.surface_cell_rows[cellRowIndex(y, z)] = std::uint16_t(complete & mixed);
}

VF_HOST_DEVICE inline void classifyCells(const Team& team, BlockSigns& s) {
    for (int r = team.rank; r < kCellRows; r += team.size)
        classifyCellRow(r % kCellRowSide - 1, r / kCellRowSide - 1, s);
}

// The neighbourhood's voxels, signs and cells; the team waits at the end. s.neighbours must be set.
template <class TVoxel, class TBlocks>
VF_HOST_DEVICE void unpackNeighbourhood(const Team& team, const TBlocks& blocks, Vec3i block, BlockSigns& s,
                                        BlockVoxels<TVoxel>& voxels) {
    for (int r = team.rank; r < kLocalRows; r += team.size)
        unpackRow<TVoxel>(blocks, block, r % kLocalSide - kMarginBelow, r / kLocalSide - kMarginBelow, s, voxels);
    team.sync();
    classifyCells(team, s);
    team.sync();
}

// The neighbourhood's signs (x, y, z = -1 .. 8) and cells from the row signs; the team waits at the end.
VF_HOST_DEVICE inline void gatherNeighbourhoodSigns(const Team& team, const RowSigns* row_signs, BlockSigns& s) {
    constexpr int side = kLocalSide - 1;
    for (int r = team.rank; r < side * side; r += team.size) gatherSignRow(row_signs, r % side - 1, r / side - 1, s);
    team.sync();
    classifyCells(team, s);
    team.sync();
}

// ---- Rows of the block: which edges carry vertices, how many triangles ----

// The edges of row (y, z), y and z in 0 .. 7, that carry a vertex: cut edges that a complete cell uses.
// The four cells around an edge start at the edge's start minus 0 or 1 along each of the two other axes.
// Bit x + 8 * axis is the edge from voxel x along `axis`.
VF_HOST_DEVICE inline unsigned rowVertexEdges(const BlockSigns& s, int y, int z) {
    auto complete = [&s](int cy, int cz) -> unsigned { return s.complete_cell_rows[cellRowIndex(cy, cz)]; };
    const unsigned o = s.observed_rows[rowIndex(y, z)], n = s.negative_rows[rowIndex(y, z)];
    const unsigned o_y = s.observed_rows[rowIndex(y + 1, z)], n_y = s.negative_rows[rowIndex(y + 1, z)];
    const unsigned o_z = s.observed_rows[rowIndex(y, z + 1)], n_z = s.negative_rows[rowIndex(y, z + 1)];
    const unsigned near_y = complete(y, z) | complete(y, z - 1), near_z = complete(y, z) | complete(y - 1, z);
    const unsigned along_x = o & (o >> 1) & (n ^ (n >> 1)) &
                             (complete(y, z) | complete(y - 1, z) | complete(y, z - 1) | complete(y - 1, z - 1));
    const unsigned along_y = o & o_y & (n ^ n_y) & (near_y | (near_y << 1));  // cells x - 1 sit one bit lower
    const unsigned along_z = o & o_z & (n ^ n_z) & (near_z | (near_z << 1));
    return ((along_x & kBlockBits) >> 1) | (((along_y & kBlockBits) >> 1) << 8) | (((along_z & kBlockBits) >> 1) << 16);
}

// Place of edge (x, axis) among the vertices of its row: the vertices of smaller x, then those of x along
// smaller axes.
VF_HOST_DEVICE inline int rankInRow(unsigned row_edges, int x, int axis) {
    const unsigned below = (1u << x) - 1u;
    const unsigned before =
        below | (below << 8) | (below << 16) | (axis > 0 ? 1u << x : 0u) | (axis > 1 ? 1u << (x + 8) : 0u);
    return bitCount(row_edges & before);
}

// The marching cubes case of the complete cell at (x, y, z) from the sign masks (all corners observed,
// so "negative" is "SDF < 0", as for cubeCase()).
VF_HOST_DEVICE inline int cellCase(const BlockSigns& s, int x, int y, int z) {
    int cube = 0;
    for (int k = 0; k < kCubeCorners; ++k) {
        const Vec3i o = cubeCornerOffset(k);
        cube |= int((s.negative_rows[rowIndex(y + o.y, z + o.z)] >> (x + o.x + 1)) & 1u) << k;
    }
    return cube;
}

VF_HOST_DEVICE inline int rowTriangleCount(const BlockSigns& s, int y, int z) {
    const MarchingCubesTable& table = marchingCubesTable();
    int count = 0;
    for (unsigned cells = s.surface_cell_rows[cellRowIndex(y, z)] & kBlockBits; cells; cells &= cells - 1)
        count += table.triangle_count[cellCase(s, lowestBit(cells) - 1, y, z)];
    return count;
}

// ---- Pass 1: count ----

// What pass 1 keeps per meshed block (slot) for pass 2.
struct MeshedBlockRows {
    int* neighbours;                    // 27 per slot: BlockSigns::neighbours, found once
    unsigned* row_edges;                // kBlockRows per slot: rowVertexEdges()
    std::uint16_t* row_first_vertex;    // kBlockRows per slot: vertices of the block's rows before this one
    std::uint16_t* row_first_triangle;  // kBlockRows per slot
    long long* vertex_count;            // per slot (long long: the scan over the slots must not overflow)
    long long* triangle_count;          // per slot
};

struct CountShared {
    BlockSigns signs;
    int row_vertices[kBlockRows];
    int row_triangles[kBlockRows];
};

template <class TBlocks>
struct CountBlockSurface {
    TBlocks blocks;
    const RowSigns* row_signs;  // per block of the list (FindRowSigns)
    const int* meshed;          // list place of each slot
    MeshedBlockRows rows;
    bool with_triangles;

    VF_HOST_DEVICE void operator()(const Team& team, int slot, CountShared& shared) const {
        const Vec3i block = blocks.position(meshed[slot]);
        for (int k = team.rank; k < 27; k += team.size) {
            const int n = blocks.find(block + Vec3i{k % 3 - 1, (k / 3) % 3 - 1, k / 9 - 1});
            shared.signs.neighbours[k] = n;
            rows.neighbours[slot * 27 + k] = n;
        }
        team.sync();
        gatherNeighbourhoodSigns(team, row_signs, shared.signs);
        for (int r = team.rank; r < kBlockRows; r += team.size) {
            const unsigned edges = rowVertexEdges(shared.signs, r % kBlockSide, r / kBlockSide);
            rows.row_edges[slot * kBlockRows + r] = edges;
            shared.row_vertices[r] = bitCount(edges);
            shared.row_triangles[r] =
                with_triangles ? rowTriangleCount(shared.signs, r % kBlockSide, r / kBlockSide) : 0;
        }
        team.sync();
        if (team.rank != 0) return;
        int vertices = 0, triangles = 0;  // at most 3 * 512 and 5 * 512
        for (int r = 0; r < kBlockRows; ++r) {
            rows.row_first_vertex[slot * kBlockRows + r] = std::uint16_t(vertices);
            rows.row_first_triangle[slot * kBlockRows + r] = std::uint16_t(triangles);
            vertices += shared.row_vertices[r];
            triangles += shared.row_triangles[r];
        }
        rows.vertex_count[slot] = vertices;
        rows.triangle_count[slot] = triangles;
    }
};

// ---- Pass 2: emit ----

// Where the surface goes (arrays of the engine's device); triangles == nullptr: vertices only.
struct SurfaceOutput {
    Vec3f* positions;
    Vec3f* normals;
    Vec3u8* colors;   // voxel types with colour
    ClassId* labels;  // voxel types with labels
    Vec3i* triangles;
    int* unresolved_corners;  // triangle corners whose edge has no vertex (none unless the scene changed)
};

template <class TVoxel>
struct EmitShared {
    BlockSigns signs;
    BlockVoxels<TVoxel> voxels;
    int owner_slot[8];  // slots of the block's 2x2x2 neighbourhood (dx + 2 dy + 4 dz), -1: not meshed
};

// The SDF gradient interpolated along the edge; where it vanishes (possible in noise), the edge's
// direction from its inside to its outside end, which also points to free space.
template <class TVoxel>
VF_HOST_DEVICE Vec3f vertexNormal(const BlockVoxels<TVoxel>& v, int start, int end, int axis, float t) {
    const Vec3f g = lerp(v.gradient(start), v.gradient(end), t);
    if (length(g) > 0.f) return normalize(g);
    Vec3f n{0.f, 0.f, 0.f};
    n[axis] = v.sdf[start] < 0.f ? 1.f : -1.f;
    return n;
}

template <class TVoxel>
VF_HOST_DEVICE Vec3u8 edgeColor(const BlockVoxels<TVoxel>& v, int start, int end, float t) {
    auto toFloat3 = [](Vec3u8 c) { return Vec3f{float(c.x), float(c.y), float(c.z)}; };
    Vec3f c{0.f, 0.f, 0.f};
    if (v.colored[start] && v.colored[end])
        c = lerp(toFloat3(v.color[start]), toFloat3(v.color[end]), t);
    else if (v.colored[start])
        c = toFloat3(v.color[start]);
    else if (v.colored[end])
        c = toFloat3(v.color[end]);
    return Vec3u8{std::uint8_t(c.x + 0.5f), std::uint8_t(c.y + 0.5f), std::uint8_t(c.z + 0.5f)};
}

// Classes cannot be interpolated: the vertex takes the class of the edge end nearer to it, or of the
// other end where the nearer one has none.
template <class TVoxel>
VF_HOST_DEVICE ClassId edgeLabel(const BlockVoxels<TVoxel>& v, int start, int end, float t) {
    const int nearer = t < 0.5f ? start : end, farther = t < 0.5f ? end : start;
    return v.label[nearer] != kNoLabel ? v.label[nearer] : v.label[farther];
}

template <class TVoxel, class TBlocks>
struct EmitBlockSurface {
    TBlocks blocks;
    const int* meshed;
    const int* slot_of_block;  // per list place
    MeshedBlockRows rows;
    const long long* first_vertex;    // per slot, from the scan (the engine checks the total fits an int)
    const long long* first_triangle;  // per slot
    float voxel_size_m;
    SurfaceOutput out;

    VF_HOST_DEVICE void operator()(const Team& team, int slot, EmitShared<TVoxel>& shared) const {
        const Vec3i block = blocks.position(meshed[slot]);
        for (int k = team.rank; k < 27; k += team.size) shared.signs.neighbours[k] = rows.neighbours[slot * 27 + k];
        if (out.triangles)
            for (int n = team.rank; n < 8; n += team.size) {
                // Offsets 0 and +1 of the 27 neighbours sit at (1 + dx) + 3 (1 + dy) + 9 (1 + dz).
                const int place = rows.neighbours[slot * 27 + 13 + (n & 1) + 3 * ((n >> 1) & 1) + 9 * ((n >> 2) & 1)];
                shared.owner_slot[n] = place >= 0 ? slot_of_block[place] : -1;
            }
        team.sync();
        unpackNeighbourhood<TVoxel>(team, blocks, block, shared.signs, shared.voxels);
        for (int r = team.rank; r < kBlockRows; r += team.size) {
            const int y = r % kBlockSide, z = r / kBlockSide;
            emitRowVertices(shared.voxels, block, y, z, rows.row_edges[slot * kBlockRows + r],
                            int(first_vertex[slot]) + rows.row_first_vertex[slot * kBlockRows + r]);
            if (out.triangles)
                emitRowTriangles(shared, y, z, first_triangle[slot] + rows.row_first_triangle[slot * kBlockRows + r]);
        }
    }

private:
    VF_HOST_DEVICE void emitRowVertices(const BlockVoxels<TVoxel>& v, Vec3i block, int y, int z, unsigned edges,
                                        int index) const {
        const Vec3i block_origin = block * kBlockSide;
        for (int x = 0; x < kBlockSide; ++x) {
            if (!((edges >> x) & 0x10101u)) continue;
            const int start = localIndex({x, y, z});
            for (int axis = 0; axis < 3; ++axis) {
                if (!((edges >> (x + 8 * axis)) & 1u)) continue;
                const int end = start + localStride(axis);
                const float t = edgeCrossing(v.sdf[start], v.sdf[end]);
                Vec3f p = toFloat(block_origin + Vec3i{x, y, z});
                p[axis] += t;
                out.positions[index] = p * voxel_size_m;
                out.normals[index] = vertexNormal(v, start, end, axis, t);
                if constexpr (TVoxel::hasColor) out.colors[index] = edgeColor(v, start, end, t);
                if constexpr (TVoxel::hasLabel) out.labels[index] = edgeLabel(v, start, end, t);
                ++index;
            }
        }
    }

    // Marching cubes over the row's complete cells that have both signs (the others have no triangles).
    VF_HOST_DEVICE void emitRowTriangles(const EmitShared<TVoxel>& shared, int y, int z, long long index) const {
        const MarchingCubesTable& table = marchingCubesTable();
        for (unsigned cells = shared.signs.surface_cell_rows[cellRowIndex(y, z)] & kBlockBits; cells;
             cells &= cells - 1) {
            const int x = lowestBit(cells) - 1;
            const int cube = cellCase(shared.signs, x, y, z);
            const int corners = 3 * table.triangle_count[cube];
            for (int k = 0; k < corners; ++k) {
                const int e = table.triangle_edges[cube][k];
                const Vec3i start = Vec3i{x, y, z} + cubeCornerOffset(cubeEdgeStartCorner(e));  // 0 .. 8 per axis
                out.triangles[index + k / 3][k % 3] = vertexOfEdge(shared, start, cubeEdgeAxis(e));
            }
            index += corners / 3;
        }
    }

    // Output index of the vertex on the edge from `start` (0 .. 8 per axis, local to this block) along
    // `axis`; -1 (counted) where there is none.
    VF_HOST_DEVICE int vertexOfEdge(const EmitShared<TVoxel>& shared, Vec3i start, int axis) const {
        const int owner = shared.owner_slot[(start.x >> 3) | ((start.y >> 3) << 1) | ((start.z >> 3) << 2)];
        const int x = start.x & 7, row = (start.y & 7) + kBlockSide * (start.z & 7);
        const unsigned edges = owner >= 0 ? rows.row_edges[owner * kBlockRows + row] : 0u;
        if (!((edges >> (x + 8 * axis)) & 1u)) {
            atomicAddInt(out.unresolved_corners, 1);
            return -1;
        }
        return int(first_vertex[owner]) + rows.row_first_vertex[owner * kBlockRows + row] + rankInRow(edges, x, axis);
    }
};

}  // namespace voxfuse::meshing
