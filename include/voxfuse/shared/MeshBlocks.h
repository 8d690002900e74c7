#pragma once
// How the meshing engine sees the scene, on either device: a list of 8x8x8 blocks with their positions,
// a lookup from a block position to its place in the list, and the voxel at a place in a block. Both
// indexes are seen this way (the hash's own blocks, or the same grid laid over the dense array), so
// that one set of loop bodies (shared/Meshing.h) serves both.
//
// The hash's blocks are listed in Morton order: a block's neighbours, which its cells read too, are
// mostly near it in the list (in cache on the CPU), the mesh comes out ordered in space, and the order
// depends on the set of blocks only, not on where the hash put them or on the device.

#include <cstdint>

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/HashTableTypes.h"
#include "voxfuse/objects/PlainVoxelArray.h"
#include "voxfuse/shared/HashAccess.h"
#include "voxfuse/shared/VoxelAccess.h"

namespace voxfuse::meshing {

// ---- Morton order ----

// Interleaves the bits of the three block coordinates, offset by 2^15 to be non-negative (block
// coordinates are within +-32767): bit 3b + a of the code is bit b of axis a.
VF_HOST_DEVICE inline std::uint64_t mortonCode(Vec3i block) {
    std::uint64_t code = 0;
    const std::uint32_t c[3] = {std::uint32_t(block.x + 0x8000), std::uint32_t(block.y + 0x8000),
                                std::uint32_t(block.z + 0x8000)};
    for (int bit = 0; bit < 17; ++bit)
        for (int a = 0; a < 3; ++a) code |= std::uint64_t((c[a] >> bit) & 1u) << (3 * bit + a);
    return code;
}

VF_HOST_DEVICE inline Vec3i mortonDecode(std::uint64_t code) {
    std::uint32_t c[3] = {0, 0, 0};
    for (int bit = 0; bit < 17; ++bit)
        for (int a = 0; a < 3; ++a) c[a] |= std::uint32_t((code >> (3 * bit + a)) & 1u) << bit;
    return {int(c[0]) - 0x8000, int(c[1]) - 0x8000, int(c[2]) - 0x8000};
}

// ---- The hash's block list ----

// Morton code of the block of each allocated entry (`entry_ids` from a selection of entries with
// ptr >= 0). Sorted, the codes are the list.
struct MortonCodeOfEntry {
    const HashEntry* entries;
    const int* entry_ids;
    std::uint64_t* codes;

    VF_HOST_DEVICE void operator()(int k) const {
        const HashEntry& e = entries[entry_ids[k]];
        codes[k] = mortonCode({e.pos.x, e.pos.y, e.pos.z});
    }
};

struct EntryHasVoxelBlock {
    const HashEntry* entries;
    VF_HOST_DEVICE bool operator()(int e) const { return entries[e].ptr >= 0; }
};

// Place i of the list: the block of the i-th sorted code, its voxel block, and the way back from the
// voxel block to i (`list_index_of_ptr`, -1 elsewhere).
struct ListHashBlock {
    HashTableView hash;
    const std::uint64_t* sorted_codes;
    Vec3i* positions;
    int* ptrs;
    int* list_index_of_ptr;

    VF_HOST_DEVICE void operator()(int i) const {
        const Vec3i block = mortonDecode(sorted_codes[i]);
        const int ptr = findVoxelBlock(hash, block);
        positions[i] = block;
        ptrs[i] = ptr;
        list_index_of_ptr[ptr] = i;
    }
};

template <class TVoxel>
struct HashMeshBlocks {
    HashTableView hash;
    const TVoxel* voxels;
    const Vec3i* positions;
    const int* ptrs;
    const int* list_index_of_ptr;
    int block_count;

    VF_HOST_DEVICE int count() const { return block_count; }
    VF_HOST_DEVICE Vec3i position(int i) const { return positions[i]; }
    // Place in the list of the block at `block`, or -1 where there is none.
    VF_HOST_DEVICE int find(Vec3i block) const {
        const int ptr = findVoxelBlock(hash, block);
        return ptr >= 0 ? list_index_of_ptr[ptr] : -1;
    }
    // The voxel at `local` (0..7 per axis) of block i, which lies at `block`.
    VF_HOST_DEVICE const TVoxel* voxel(Vec3i /*block*/, int i, Vec3i local) const {
        return voxels + std::size_t(ptrs[i]) * kBlockVoxelCount + voxelIndexInBlock(local);
    }
};

// ---- The dense array as blocks ----

// The grid of 8x8x8 blocks (aligned as the hash's) covering the array, x-fastest.
template <class TVoxel>
struct DenseMeshBlocks {
    PlainVoxelArray::Data index;
    const TVoxel* voxels;
    Vec3i first, counts;

    static DenseMeshBlocks make(const PlainVoxelArray::Data& index, const TVoxel* voxels) {
        const Vec3i first = blockOfVoxel(index.offset);
        const Vec3i last = blockOfVoxel(index.offset + index.size - Vec3i{1, 1, 1});
        return {index, voxels, first, last - first + Vec3i{1, 1, 1}};
    }
    VF_HOST_DEVICE int count() const { return counts.x * counts.y * counts.z; }
    VF_HOST_DEVICE Vec3i position(int i) const {
        return first + Vec3i{i % counts.x, (i / counts.x) % counts.y, i / (counts.x * counts.y)};
    }
    VF_HOST_DEVICE int find(Vec3i block) const {
        const Vec3i b = block - first;
        if (b.x < 0 || b.y < 0 || b.z < 0 || b.x >= counts.x || b.y >= counts.y || b.z >= counts.z) return -1;
        return b.x + counts.x * (b.y + counts.y * b.z);
    }
    // The voxel at `local` (0..7 per axis) of the block at `block`, or nullptr beyond the array.
    VF_HOST_DEVICE const TVoxel* voxel(Vec3i block, int /*i*/, Vec3i local) const {
        const long long offset = denseVoxelOffset(index, block * kBlockSide + local);
        return offset >= 0 ? voxels + offset : nullptr;
    }
};

// ---- Which blocks can hold surface ----

// The signs of every block as bit masks, one pair of bytes per row of 8 voxels along x (row
// y + 8 z; bit x): the count pass builds its neighbourhoods from these instead of reading voxels again.
struct RowSigns {
    std::uint8_t observed;  // weight > 0
    std::uint8_t negative;  // observed and SDF < 0
};
constexpr int kRowsPerBlock = kBlockSide * kBlockSide;

// Row r of block i, for i * 64 + r.
template <class TVoxel, class TBlocks>
struct FindRowSigns {
    TBlocks blocks;
    RowSigns* row_signs;

    VF_HOST_DEVICE void operator()(int k) const {
        const int i = k / kRowsPerBlock, r = k % kRowsPerBlock;
        const Vec3i block = blocks.position(i);
        unsigned observed = 0, negative = 0;
        for (int x = 0; x < kBlockSide; ++x) {
            const TVoxel* v = blocks.voxel(block, i, Vec3i{x, r % kBlockSide, r / kBlockSide});
            if (!v || v->w_depth == 0) continue;
            observed |= 1u << x;
            negative |= unsigned(TVoxel::sdfToFloat(v->sdf) < 0.f) << x;
        }
        row_signs[k] = {std::uint8_t(observed), std::uint8_t(negative)};
    }
};

constexpr std::uint8_t kHasNegative = 1, kHasPositive = 2;

// Which signs the observed voxels of block i have (kHasNegative | kHasPositive).
struct SummariseBlockSigns {
    const RowSigns* row_signs;
    std::uint8_t* signs;

    VF_HOST_DEVICE void operator()(int i) const {
        unsigned any_negative = 0, any_positive = 0;
        for (int r = 0; r < kRowsPerBlock; ++r) {
            const RowSigns rs = row_signs[i * kRowsPerBlock + r];
            any_negative |= rs.negative;
            any_positive |= rs.observed & ~unsigned(rs.negative);
        }
        signs[i] = std::uint8_t((any_negative ? kHasNegative : 0) | (any_positive ? kHasPositive : 0));
    }
};

// A block's cells and edges read voxels of the block and of its seven neighbours above only: without
// both signs among them it has neither vertices nor triangles.
template <class TBlocks>
struct BlockMayHoldSurface {
    TBlocks blocks;
    const std::uint8_t* signs;

    VF_HOST_DEVICE bool operator()(int i) const {
        const Vec3i block = blocks.position(i);
        std::uint8_t s = 0;
        for (int k = 0; k < 8; ++k) {
            const int n = k == 0 ? i : blocks.find(block + Vec3i{k & 1, (k >> 1) & 1, (k >> 2) & 1});
            if (n >= 0) s |= signs[n];
        }
        return s == (kHasNegative | kHasPositive);
    }
};

// The way from a list place to the block's slot among those meshed (-1 for the others).
struct SlotOfMeshedBlock {
    const int* meshed;
    int* slot_of_block;
    VF_HOST_DEVICE void operator()(int slot) const { slot_of_block[meshed[slot]] = slot; }
};

}  // namespace voxfuse::meshing
