#pragma once
// How the CPU meshing layer reads the scene: block by block, each with a margin from its neighbours.
// Both indexes are seen as a grid of 8x8x8 blocks (the hash's own, or the same grid laid over the
// dense array), so that one loop serves both. Private to src/cpu/MeshingEngine_CPU.cpp.

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "engines/DeviceImages.h"
#include "voxfuse/objects/PlainVoxelArray.h"
#include "voxfuse/objects/Scene.h"
#include "voxfuse/objects/VoxelBlockHash.h"
#include "voxfuse/shared/MarchingCubes.h"
#include "voxfuse/shared/VoxelAccess.h"

namespace voxfuse::cpu::meshing {

// ---- The blocks of each index: count, position, lookup by position, and a voxel of a block (the block
// is passed both ways, so that neither index has to recompute it) ----

// Interleaves the bits of the three block coordinates (offset to be non-negative): blocks close in
// this order are close in space.
inline std::uint64_t mortonCode(Vec3i block) {
    std::uint64_t code = 0;
    const std::uint32_t c[3] = {std::uint32_t(block.x + 0x8000), std::uint32_t(block.y + 0x8000), std::uint32_t(block.z + 0x8000)};
    for (int bit = 0; bit < 17; ++bit)
        for (int a = 0; a < 3; ++a) code |= std::uint64_t((c[a] >> bit) & 1u) << (3 * bit + a);
    return code;
}

// Every allocated block of the hash, in Morton order: a block's neighbours, which it reads too, were
// mostly read shortly before (the voxels stay in cache), and the output is ordered in space.
template <class TVoxel>
class HashBlocks {
public:
    explicit HashBlocks(const Scene<TVoxel, VoxelBlockHash>& scene) : hash_(scene.index().data()), voxels_(scene.voxels().host()) {
        requireSceneOn(Device::CPU, scene, "meshing");
        const VoxelBlockHash& index = scene.index();
        std::vector<std::pair<std::uint64_t, int>> order;  // (Morton code, entry); codes are unique as blocks are
        for (int e = 0; e < index.entryCount(); ++e) {
            const HashEntry& entry = index.entry(e);
            if (entry.ptr >= 0) order.push_back({mortonCode({entry.pos.x, entry.pos.y, entry.pos.z}), e});
        }
        std::sort(order.begin(), order.end());
        list_index_of_ptr_.assign(std::size_t(index.blockCapacity()), -1);
        for (const auto& code_and_entry : order) {
            const HashEntry& entry = index.entry(code_and_entry.second);
            list_index_of_ptr_[std::size_t(entry.ptr)] = int(positions_.size());
            positions_.push_back({entry.pos.x, entry.pos.y, entry.pos.z});
            ptrs_.push_back(entry.ptr);
        }
    }
    int count() const { return int(positions_.size()); }
    Vec3i position(int i) const { return positions_[std::size_t(i)]; }
    int find(Vec3i block) const {
        const int ptr = findVoxelBlock(hash_, block);
        return ptr >= 0 ? list_index_of_ptr_[std::size_t(ptr)] : -1;
    }
    // The voxel at `local` (0..7 per axis) of block i, which lies at `block`.
    const TVoxel* voxel(Vec3i /*block*/, int i, Vec3i local) const {
        return voxels_ + std::size_t(ptrs_[std::size_t(i)]) * kBlockVoxelCount + voxelIndexInBlock(local);
    }

private:
    VoxelBlockHash::Data hash_;
    const TVoxel* voxels_;
    std::vector<Vec3i> positions_;
    std::vector<int> ptrs_;
    std::vector<int> list_index_of_ptr_;
};

// The grid of 8x8x8 blocks (aligned as the hash's) covering the dense array, x-fastest.
template <class TVoxel>
class DenseBlocks {
public:
    explicit DenseBlocks(const Scene<TVoxel, PlainVoxelArray>& scene) : index_(scene.index().data()), voxels_(scene.voxels().host()) {
        requireSceneOn(Device::CPU, scene, "meshing");
        first_ = blockOfVoxel(index_.offset);
        counts_ = blockOfVoxel(index_.offset + index_.size - Vec3i{1, 1, 1}) - first_ + Vec3i{1, 1, 1};
    }
    int count() const { return counts_.x * counts_.y * counts_.z; }
    Vec3i position(int i) const { return first_ + Vec3i{i % counts_.x, (i / counts_.x) % counts_.y, i / (counts_.x * counts_.y)}; }
    int find(Vec3i block) const {
        const Vec3i b = block - first_;
        if (b.x < 0 || b.y < 0 || b.z < 0 || b.x >= counts_.x || b.y >= counts_.y || b.z >= counts_.z) return -1;
        return b.x + counts_.x * (b.y + counts_.y * b.z);
    }
    // The voxel at `local` (0..7 per axis) of the block at `block`, or nullptr beyond the array.
    const TVoxel* voxel(Vec3i block, int /*i*/, Vec3i local) const {
        const long long offset = denseVoxelOffset(index_, block * kBlockSide + local);
        return offset >= 0 ? voxels_ + offset : nullptr;
    }

private:
    PlainVoxelArray::Data index_;
    const TVoxel* voxels_;
    Vec3i first_, counts_;
};

// ---- One block's neighbourhood, unpacked ----

// Local coordinates -1 .. 9 per axis: the block's cells reach +1, the cells around its edges reach -1,
// and the gradients at its edges' far ends reach +2.
constexpr int kMarginBelow = 1, kMarginAbove = 2;
constexpr int kLocalSide = kBlockSide + kMarginBelow + kMarginAbove;
constexpr int kLocalCount = kLocalSide * kLocalSide * kLocalSide;
constexpr int kLocalStride[3] = {1, kLocalSide, kLocalSide * kLocalSide};
// Rows of cells whose first corner is at y, z = -1 .. 7.
constexpr int kCellRowSide = kBlockSide + 1;
// Bit x + 1 of a row mask stands for x = -1 .. 9; bits 1 .. 8 are x = 0 .. 7, the block's own.
constexpr std::uint16_t kBlockBits = 0x1FE;

inline int localIndex(Vec3i l) { return (l.x + kMarginBelow) + kLocalSide * ((l.y + kMarginBelow) + kLocalSide * (l.z + kMarginBelow)); }
inline int rowIndex(int y, int z) { return (y + kMarginBelow) + kLocalSide * (z + kMarginBelow); }
inline int cellRowIndex(int y, int z) { return (y + 1) + kCellRowSide * (z + 1); }

// Edge ids within a block: (voxel index in the block) * 3 + axis, below 2^11. A triangle refers to an
// edge of its block's 2x2x2 neighbourhood as (neighbour << 11) | id, neighbour = dx + 2 dy + 4 dz.
constexpr int kEdgesPerBlock = kBlockVoxelCount * 3;
constexpr int kEdgeIdBits = 11;
static_assert(kEdgesPerBlock <= (1 << kEdgeIdBits), "edge ids fit in 11 bits");
inline int edgeId(Vec3i local_in_block, int axis) { return voxelIndexInBlock(local_in_block) * 3 + axis; }

// The voxels as floats, and bit masks per row along x of which are observed, which are negative and
// which cells are complete: whole rows of cells and edges are tested at once, and only the few on the
// surface are visited one by one.
template <class TVoxel>
struct LocalVolume {
    float sdf[kLocalCount];
    bool observed[kLocalCount];
    Vec3u8 color[TVoxel::hasColor ? kLocalCount : 1];
    bool colored[TVoxel::hasColor ? kLocalCount : 1];
    ClassId label[TVoxel::hasLabel ? kLocalCount : 1];  // kNoLabel where unobserved or without a class (w_label == 0)
    std::uint16_t observed_rows[kLocalSide * kLocalSide];
    std::uint16_t negative_rows[kLocalSide * kLocalSide];         // observed and SDF < 0
    std::uint16_t complete_cell_rows[kCellRowSide * kCellRowSide];  // all eight corners observed
    std::uint16_t surface_cell_rows[kCellRowSide * kCellRowSide];   // complete, with both signs

    template <class TBlocks>
    void fill(const TBlocks& blocks, Vec3i block) {
        int neighbours[27];
        for (int k = 0; k < 27; ++k) neighbours[k] = blocks.find(block + Vec3i{k % 3 - 1, (k / 3) % 3 - 1, k / 9 - 1});
        for (int z = -kMarginBelow; z < kBlockSide + kMarginAbove; ++z)
            for (int y = -kMarginBelow; y < kBlockSide + kMarginAbove; ++y) {
                // (c + 8) >> 3 is 0, 1 or 2 for c = -1 .. 9: the neighbour below, this block, the one above.
                const int ny = (y + 8) >> 3, nz = (z + 8) >> 3;
                std::uint16_t observed_bits = 0, negative_bits = 0;
                int i = localIndex({-kMarginBelow, y, z});
                for (int x = -kMarginBelow; x < kBlockSide + kMarginAbove; ++x, ++i) {
                    const int nx = (x + 8) >> 3;
                    const int n = neighbours[nx + 3 * ny + 9 * nz];
                    const TVoxel* v = n >= 0 ? blocks.voxel(block + Vec3i{nx - 1, ny - 1, nz - 1}, n, Vec3i{x & 7, y & 7, z & 7}) : nullptr;
                    observed[i] = v && v->w_depth > 0;
                    sdf[i] = observed[i] ? TVoxel::sdfToFloat(v->sdf) : 1.f;
                    observed_bits |= std::uint16_t(observed[i]) << (x + 1);
                    negative_bits |= std::uint16_t(observed[i] && sdf[i] < 0.f) << (x + 1);
                    if constexpr (TVoxel::hasColor) {
                        colored[i] = observed[i] && v->w_color > 0;
                        color[i] = colored[i] ? v->clr : Vec3u8{0, 0, 0};
                    }
                    if constexpr (TVoxel::hasLabel) label[i] = observed[i] && v->w_label > 0 ? v->label : kNoLabel;
                }
                observed_rows[rowIndex(y, z)] = observed_bits;
                negative_rows[rowIndex(y, z)] = negative_bits;
            }
        // A cell at x uses voxels x and x + 1 of four rows: bit x + 1 of A & (A >> 1).
        for (int z = -1; z < kBlockSide; ++z)
            for (int y = -1; y < kBlockSide; ++y) {
                const int r[4] = {rowIndex(y, z), rowIndex(y + 1, z), rowIndex(y, z + 1), rowIndex(y + 1, z + 1)};
                const unsigned all_observed = observed_rows[r[0]] & observed_rows[r[1]] & observed_rows[r[2]] & observed_rows[r[3]];
                const unsigned any_negative = negative_rows[r[0]] | negative_rows[r[1]] | negative_rows[r[2]] | negative_rows[r[3]];
                const unsigned all_negative = negative_rows[r[0]] & negative_rows[r[1]] & negative_rows[r[2]] & negative_rows[r[3]];
                const unsigned complete = all_observed & (all_observed >> 1) & 0x1FFu;
                const unsigned mixed = (any_negative | (any_negative >> 1)) & ~(all_negative & (all_negative >> 1));
                complete_cell_rows[cellRowIndex(y, z)] = std::uint16_t(complete);
                surface_cell_rows[cellRowIndex(y, z)] = std::uint16_t(complete & mixed);
            }
    }

    static int cornerStep(int corner) {
        const Vec3i o = cubeCornerOffset(corner);
        return o.x * kLocalStride[0] + o.y * kLocalStride[1] + o.z * kLocalStride[2];
    }

    Vec3f gradient(int i) const {
        Vec3f g;
        for (int a = 0; a < 3; ++a) {
            const int s = kLocalStride[a];
            g[a] = sdfDifference(sdf[i - s], observed[i - s], sdf[i], sdf[i + s], observed[i + s]);
        }
        return g;
    }
};

// Index of the lowest set bit (the mask is not zero).
inline int lowestBit(unsigned mask) { return __builtin_ctz(mask); }

}  // namespace voxfuse::cpu::meshing
