// CPU/OpenMP loops of the meshing engine; the per-cell work is in shared/MarchingCubes.h.
//
// The scene is walked in blocks of 8x8x8 cells (BlockNeighbourhood_CPU.h), the same way for both
// indexes. A vertex lies on a voxel edge and belongs to the block holding the edge's start voxel,
// which makes it exactly once however many cells and blocks use it.
// Pass 1, in parallel over blocks: a block is skipped unless the observed voxels of its 2x2x2 block
// neighbourhood (all that its cells and edges read) change sign. The others unpack their voxels and a
// margin into a small local volume, then append their vertices (ascending by edge) and their triangles
// (as references to edges of this block or of a neighbour) to the lists of their thread.
// A prefix sum over the blocks, in block order, places each block's vertices in the output.
// Pass 2, in parallel: vertices are copied to their place, and each triangle reference is resolved
// through a per-thread table of the output indices of the edges of the block's 2x2x2 neighbourhood.
// Memory is the per-thread lists plus the output (both proportional to the surface, together about
// twice the final mesh) and a few bytes per block.

#include <omp.h>

#include <algorithm>
#include <climits>
#include <cstdint>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "BlockNeighbourhood_CPU.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/MeshingEngine.h"
#include "voxfuse/engines/EnginePairs.h"
#include "voxfuse/objects/Voxel.h"

namespace voxfuse::cpu {
namespace {

using namespace meshing;

// ---- Per-thread output of pass 1 ----

struct ThreadLists {
    std::vector<Vec3f> positions, normals;
    std::vector<Vec3u8> colors;
    std::vector<ClassId> labels;
    std::vector<std::uint16_t> edge_ids;       // per vertex, ascending within a block
    std::vector<std::uint16_t> triangle_refs;  // three per triangle
};

// Pass 2, per thread: output vertex index of each edge of the 2x2x2 blocks around the block at hand.
struct VertexLookup {
    int index[8][kEdgesPerBlock];
    int stamp[8][kEdgesPerBlock];  // block index + 1 that wrote the entry
};

struct BlockOutput {
    int thread = -1;
    std::size_t first_vertex = 0, first_ref = 0;  // in the thread's lists
    int vertex_count = 0, triangle_count = 0;
};

// Where the extracted surface goes (a mesh, or a point cloud without triangles).
struct SurfaceArrays {
    std::vector<Vec3f>& positions;
    std::vector<Vec3f>& normals;
    std::vector<Vec3u8>& colors;
    std::vector<ClassId>& labels;
    std::vector<Vec3i>* triangles;  // nullptr: vertices only
};

template <class TVoxel, class TBlocks>
class SurfaceExtraction {
public:
    SurfaceExtraction(const TBlocks& blocks, float voxel_size_m) : blocks_(blocks), voxel_size_m_(voxel_size_m) {}

    void run(SurfaceArrays out) {
        const int block_count = blocks_.count();
        findBlockSigns();
        const int threads = omp_get_max_threads();
        std::vector<ThreadLists> lists(static_cast<std::size_t>(threads));
        std::vector<BlockOutput> outputs(static_cast<std::size_t>(block_count));
        const bool with_triangles = out.triangles != nullptr;

        // An exception must not leave an OpenMP region: running out of memory is noted and reported after it.
        bool out_of_memory = false;
#pragma omp parallel reduction(|| : out_of_memory)
        {
            const int thread = omp_get_thread_num();
            ThreadLists& mine = lists[std::size_t(thread)];
            const auto local = std::make_unique<LocalVolume<TVoxel>>();
#pragma omp for schedule(dynamic, 16)
            for (int i = 0; i < block_count; ++i) {
                const Vec3i block = blocks_.position(i);
                if (out_of_memory || !mayHoldSurface(block)) continue;
                local->fill(blocks_, block);
                BlockOutput& o = outputs[std::size_t(i)];
                o.thread = thread;
                o.first_vertex = mine.positions.size();
                o.first_ref = mine.triangle_refs.size();
                try {
                    appendVertices(*local, block, mine);
                    if (with_triangles) appendTriangles(*local, mine);
                } catch (const std::bad_alloc&) {
                    out_of_memory = true;
                }
                o.vertex_count = int(mine.positions.size() - o.first_vertex);
                o.triangle_count = int((mine.triangle_refs.size() - o.first_ref) / 3);
            }
        }
        if (out_of_memory) throw Error("meshing: out of memory while collecting the surface");

        // Output places in block order, so the result does not depend on the thread count.
        std::vector<std::size_t> first_vertex(std::size_t(block_count) + 1, 0), first_triangle(std::size_t(block_count) + 1, 0);
        for (int i = 0; i < block_count; ++i) {
            first_vertex[std::size_t(i) + 1] = first_vertex[std::size_t(i)] + std::size_t(outputs[std::size_t(i)].vertex_count);
            first_triangle[std::size_t(i) + 1] = first_triangle[std::size_t(i)] + std::size_t(outputs[std::size_t(i)].triangle_count);
        }
        const std::size_t vertex_count = first_vertex.back();
        if (vertex_count > std::size_t(INT_MAX)) throw Error("meshing: more than 2^31 vertices");
        out.positions.resize(vertex_count);
        out.normals.resize(vertex_count);
        out.colors.resize(TVoxel::hasColor ? vertex_count : 0);
        out.labels.resize(TVoxel::hasLabel ? vertex_count : 0);
        if (with_triangles) out.triangles->resize(first_triangle.back());

        int unresolved = 0;
#pragma omp parallel reduction(+ : unresolved)
        {
            const auto lookup = with_triangles ? std::make_unique<VertexLookup>() : nullptr;
            if (lookup) std::fill(&lookup->stamp[0][0], &lookup->stamp[0][0] + 8 * kEdgesPerBlock, 0);
#pragma omp for schedule(dynamic, 64)
            for (int i = 0; i < block_count; ++i) {
                const BlockOutput& o = outputs[std::size_t(i)];
                if (o.thread < 0) continue;
                const ThreadLists& src = lists[std::size_t(o.thread)];
                const auto from = std::ptrdiff_t(o.first_vertex), to = std::ptrdiff_t(first_vertex[std::size_t(i)]);
                std::copy_n(src.positions.begin() + from, o.vertex_count, out.positions.begin() + to);
                std::copy_n(src.normals.begin() + from, o.vertex_count, out.normals.begin() + to);
                if constexpr (TVoxel::hasColor) std::copy_n(src.colors.begin() + from, o.vertex_count, out.colors.begin() + to);
                if constexpr (TVoxel::hasLabel) std::copy_n(src.labels.begin() + from, o.vertex_count, out.labels.begin() + to);
                if (lookup)
                    unresolved += resolveTriangles(i, outputs, lists, first_vertex, *lookup, out.triangles->data() + first_triangle[std::size_t(i)]);
            }
        }
        if (unresolved > 0)
            throw Error("meshing: " + std::to_string(unresolved) + " triangle corners refer to no vertex (the scene changed during meshing?)");
    }

private:
    static constexpr std::uint8_t kHasNegative = 1, kHasPositive = 2;

    // Which signs the observed voxels of each block have.
    void findBlockSigns() {
        const int block_count = blocks_.count();
        signs_.assign(std::size_t(block_count), 0);
#pragma omp parallel for schedule(dynamic, 64)
        for (int i = 0; i < block_count; ++i) {
            const Vec3i block = blocks_.position(i);
            std::uint8_t s = 0;
            for (int k = 0; k < kBlockVoxelCount && s != (kHasNegative | kHasPositive); ++k) {
                const TVoxel* v = blocks_.voxel(block, i, Vec3i{k & 7, (k >> 3) & 7, k >> 6});
                if (!v || v->w_depth == 0) continue;
                s |= TVoxel::sdfToFloat(v->sdf) < 0.f ? kHasNegative : kHasPositive;
            }
            signs_[std::size_t(i)] = s;
        }
    }

    // A block's cells and edges read voxels of the block and of its neighbours above only: without a
    // sign change among them it has neither vertices nor triangles.
    bool mayHoldSurface(Vec3i block) const {
        std::uint8_t s = 0;
        for (int k = 0; k < 8; ++k) {
            const int n = blocks_.find(block + cubeCornerOffset(k));
            if (n >= 0) s |= signs_[std::size_t(n)];
        }
        return s == (kHasNegative | kHasPositive);
    }

    // The vertices of the edges that start in this block, in edge id order: cut edges that a complete
    // cell uses. The four cells around an edge start at the edge's start minus 0 or 1 along each of
    // the two other axes.
    void appendVertices(const LocalVolume<TVoxel>& v, Vec3i block, ThreadLists& out) const {
        const Vec3i block_origin = block * kBlockSide;
        auto complete = [&v](int y, int z) -> unsigned { return v.complete_cell_rows[cellRowIndex(y, z)]; };
        for (int z = 0; z < kBlockSide; ++z)
            for (int y = 0; y < kBlockSide; ++y) {
                const unsigned o = v.observed_rows[rowIndex(y, z)], n = v.negative_rows[rowIndex(y, z)];
                const unsigned o_y = v.observed_rows[rowIndex(y + 1, z)], n_y = v.negative_rows[rowIndex(y + 1, z)];
                const unsigned o_z = v.observed_rows[rowIndex(y, z + 1)], n_z = v.negative_rows[rowIndex(y, z + 1)];
                const unsigned near_y = complete(y, z) | complete(y, z - 1), near_z = complete(y, z) | complete(y - 1, z);
                unsigned edges[3];
                edges[0] = o & (o >> 1) & (n ^ (n >> 1)) & (complete(y, z) | complete(y - 1, z) | complete(y, z - 1) | complete(y - 1, z - 1));
                edges[1] = o & o_y & (n ^ n_y) & (near_y | (near_y << 1));  // cells x - 1 sit one bit lower
                edges[2] = o & o_z & (n ^ n_z) & (near_z | (near_z << 1));
                for (unsigned any = (edges[0] | edges[1] | edges[2]) & kBlockBits; any; any &= any - 1) {
                    const int bit = lowestBit(any);
                    const Vec3i l{bit - 1, y, z};
                    const int start = localIndex(l);
                    for (int axis = 0; axis < 3; ++axis) {
                        if (!((edges[axis] >> bit) & 1u)) continue;
                        const int end = start + kLocalStride[axis];
                        const float t = edgeCrossing(v.sdf[start], v.sdf[end]);
                        Vec3f p = toFloat(block_origin + l);
                        p[axis] += t;
                        out.positions.push_back(p * voxel_size_m_);
                        out.normals.push_back(vertexNormal(v, start, end, axis, t));
                        if constexpr (TVoxel::hasColor) out.colors.push_back(edgeColor(v, start, end, t));
                        if constexpr (TVoxel::hasLabel) out.labels.push_back(edgeLabel(v, start, end, t));
                        out.edge_ids.push_back(std::uint16_t(edgeId(l, axis)));
                    }
                }
            }
    }

    // The SDF gradient interpolated along the edge; where it vanishes (possible in noise), the edge's
    // direction from its inside to its outside end, which also points to free space.
    static Vec3f vertexNormal(const LocalVolume<TVoxel>& v, int start, int end, int axis, float t) {
        const Vec3f g = lerp(v.gradient(start), v.gradient(end), t);
        if (length(g) > 0.f) return normalize(g);
        Vec3f n{0.f, 0.f, 0.f};
        n[axis] = v.sdf[start] < 0.f ? 1.f : -1.f;
        return n;
    }

    static Vec3u8 edgeColor(const LocalVolume<TVoxel>& v, int start, int end, float t) {
        auto toFloat3 = [](Vec3u8 c) { return Vec3f{float(c.x), float(c.y), float(c.z)}; };
        Vec3f c{0.f, 0.f, 0.f};
        if (v.colored[start] && v.colored[end]) c = lerp(toFloat3(v.color[start]), toFloat3(v.color[end]), t);
        else if (v.colored[start]) c = toFloat3(v.color[start]);
        else if (v.colored[end]) c = toFloat3(v.color[end]);
        return Vec3u8{std::uint8_t(c.x + 0.5f), std::uint8_t(c.y + 0.5f), std::uint8_t(c.z + 0.5f)};
    }

    // Classes cannot be interpolated: the vertex takes the class of the edge end nearer to it, or of
    // the other end where the nearer one has none.
    static ClassId edgeLabel(const LocalVolume<TVoxel>& v, int start, int end, float t) {
        const int nearer = t < 0.5f ? start : end, farther = t < 0.5f ? end : start;
        return v.label[nearer] != kNoLabel ? v.label[nearer] : v.label[farther];
    }

    // Marching cubes over the block's complete cells that have both signs (the others have no triangles).
    static void appendTriangles(const LocalVolume<TVoxel>& v, ThreadLists& out) {
        const MarchingCubesTable& table = marchingCubesTable();
        for (int z = 0; z < kBlockSide; ++z)
            for (int y = 0; y < kBlockSide; ++y)
                for (unsigned cells = v.surface_cell_rows[cellRowIndex(y, z)] & kBlockBits; cells; cells &= cells - 1) {
                    const Vec3i cell{lowestBit(cells) - 1, y, z};
                    const int first = localIndex(cell);
                    float corners[kCubeCorners];
                    for (int k = 0; k < kCubeCorners; ++k) corners[k] = v.sdf[first + LocalVolume<TVoxel>::cornerStep(k)];
                    const int cube = cubeCase(corners);
                    const int edges = 3 * table.triangle_count[cube];
                    for (int k = 0; k < edges; ++k) {
                        const int e = table.triangle_edges[cube][k];
                        const Vec3i start = cell + cubeCornerOffset(cubeEdgeStartCorner(e));  // 0 .. 8 per axis
                        const int neighbour = (start.x >> 3) | ((start.y >> 3) << 1) | ((start.z >> 3) << 2);
                        const int id = edgeId(Vec3i{start.x & 7, start.y & 7, start.z & 7}, cubeEdgeAxis(e));
                        out.triangle_refs.push_back(std::uint16_t((neighbour << kEdgeIdBits) | id));
                    }
                }
    }

    // Writes block i's triangles as output vertex indices; returns how many references found no vertex.
    // `lookup` maps the edge ids of the 2x2x2 blocks above block i to output indices, valid where its
    // stamp is i + 1 (so it is never cleared).
    int resolveTriangles(int i, const std::vector<BlockOutput>& outputs, const std::vector<ThreadLists>& lists,
                         const std::vector<std::size_t>& first_vertex, VertexLookup& lookup, Vec3i* triangles) const {
        const BlockOutput& o = outputs[std::size_t(i)];
        const std::uint16_t* refs = lists[std::size_t(o.thread)].triangle_refs.data() + o.first_ref;
        const int ref_count = 3 * o.triangle_count;
        unsigned needed = 0;
        for (int k = 0; k < ref_count; ++k) needed |= 1u << (refs[k] >> kEdgeIdBits);
        const Vec3i block = blocks_.position(i);
        for (int n = 0; n < 8; ++n) {
            if (!((needed >> n) & 1u)) continue;
            const int owner = n == 0 ? i : blocks_.find(block + cubeCornerOffset(n));
            if (owner < 0 || outputs[std::size_t(owner)].thread < 0) continue;
            const BlockOutput& b = outputs[std::size_t(owner)];
            const std::uint16_t* ids = lists[std::size_t(b.thread)].edge_ids.data() + b.first_vertex;
            for (int r = 0; r < b.vertex_count; ++r) {
                lookup.index[n][ids[r]] = int(first_vertex[std::size_t(owner)]) + r;
                lookup.stamp[n][ids[r]] = i + 1;
            }
        }
        int unresolved = 0;
        for (int k = 0; k < ref_count; ++k) {
            const int n = refs[k] >> kEdgeIdBits, id = refs[k] & ((1 << kEdgeIdBits) - 1);
            const bool found = lookup.stamp[n][id] == i + 1;
            unresolved += !found;
            triangles[k / 3][k % 3] = found ? lookup.index[n][id] : -1;
        }
        return unresolved;
    }

    const TBlocks& blocks_;
    float voxel_size_m_;
    std::vector<std::uint8_t> signs_;
};

template <class TVoxel, class TBlocks>
void extract(const TBlocks& blocks, float voxel_size_m, SurfaceArrays out) {
    SurfaceExtraction<TVoxel, TBlocks>(blocks, voxel_size_m).run(out);
}

template <class TVoxel, class TIndex>
class MeshingEngine_CPU;

template <class TVoxel>
class MeshingEngine_CPU<TVoxel, PlainVoxelArray> final : public MeshingEngine<TVoxel, PlainVoxelArray> {
public:
    void extractMesh(const Scene<TVoxel, PlainVoxelArray>& scene, Mesh& mesh) override {
        mesh.clear();
        extract<TVoxel>(DenseBlocks<TVoxel>(scene), scene.params().voxel_size_m,
                        {mesh.vertices, mesh.normals, mesh.colors, mesh.labels, &mesh.triangles});
    }
    void extractPointCloud(const Scene<TVoxel, PlainVoxelArray>& scene, PointCloud& cloud) override {
        cloud.clear();
        extract<TVoxel>(DenseBlocks<TVoxel>(scene), scene.params().voxel_size_m,
                        {cloud.points, cloud.normals, cloud.colors, cloud.labels, nullptr});
    }
};

template <class TVoxel>
class MeshingEngine_CPU<TVoxel, VoxelBlockHash> final : public MeshingEngine<TVoxel, VoxelBlockHash> {
public:
    void extractMesh(const Scene<TVoxel, VoxelBlockHash>& scene, Mesh& mesh) override {
        mesh.clear();
        extract<TVoxel>(HashBlocks<TVoxel>(scene), scene.params().voxel_size_m,
                        {mesh.vertices, mesh.normals, mesh.colors, mesh.labels, &mesh.triangles});
    }
    void extractPointCloud(const Scene<TVoxel, VoxelBlockHash>& scene, PointCloud& cloud) override {
        cloud.clear();
        extract<TVoxel>(HashBlocks<TVoxel>(scene), scene.params().voxel_size_m,
                        {cloud.points, cloud.normals, cloud.colors, cloud.labels, nullptr});
    }
};

}  // namespace

template <class TVoxel, class TIndex>
std::unique_ptr<MeshingEngine<TVoxel, TIndex>> makeMeshingEngine() {
    return std::make_unique<MeshingEngine_CPU<TVoxel, TIndex>>();
}

#define VF_INSTANTIATE(TVoxel, TIndex) template std::unique_ptr<MeshingEngine<TVoxel, TIndex>> makeMeshingEngine<TVoxel, TIndex>();
VF_FOR_EACH_ENGINE_PAIR(VF_INSTANTIATE)
#undef VF_INSTANTIATE

}  // namespace voxfuse::cpu
