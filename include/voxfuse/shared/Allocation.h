#pragma once
// Allocation stage 1 for one depth pixel (section 4.2 of the InfiniTAM report): which voxel blocks the
// pixel's measurement needs. Plus the emptiness test of block removal.
//
// Integration gives a voxel a signed distance below +1 when it projects into a pixel with depth d and
// its own depth z lies in [d - mu, d + mu). Those voxels lie in the pixel's footprint between the
// depths d - mu and d + mu: within half a pixel (sideways) of the segment of the pixel's centre ray
// between those depths. Stage 1 visits every block whose box of voxel centres, grown by that half
// pixel and one voxel (the voxels' neighbours) on every axis, the segment passes through: no block
// such a voxel or its neighbour lies in is missed.

#include <cstdint>

#include "voxfuse/core/Atomics.h"
#include "voxfuse/core/Math.h"
#include "voxfuse/core/Team.h"
#include "voxfuse/objects/HashTableTypes.h"
#include "voxfuse/objects/Intrinsics.h"
#include "voxfuse/shared/BlockProjection.h"
#include "voxfuse/shared/HashAccess.h"
#include "voxfuse/shared/HashUpdate.h"

namespace voxfuse {

// The per-frame constants of stage 1 (trivially copyable).
struct DepthSegmentFrame {
    Mat4f T_grid_camera;             // depth camera coordinates (metres) -> voxel grid coordinates
    Intrinsics intrinsics;           // of the depth camera
    const float* depth;              // metres, 0 = invalid
    float mu_m;                      // truncation band
    float min_depth_m, max_depth_m;  // depth samples outside are ignored (as integration does)
    float near_m;                    // segments start no closer than this
    float margin_voxels_per_m;       // half a pixel's diagonal footprint per metre of depth, in voxels
};

// Segments beyond this many voxels from the origin need blocks no entry can store (int16 coordinates).
constexpr float kAddressableVoxelRange = float((kMaxBlockCoordinate + 1) * kBlockSide);

// Beyond the footprint, blocks get one voxel more on every side: the marching-cubes cells and the
// trilinear reads around a voxel the band updates reach its neighbours, which lie in front of their
// own pixel's depth at silhouettes (and would otherwise stay unallocated, leaving holes where the
// dense index closes the surface). Plus float rounding of the transforms: far above float's error at
// the coordinates an int16 block can have.
constexpr float kSegmentMarginExtraVoxels = 1.01f;

// Pixel (x, y)'s depth segment a -> b (grid units) and its candidate blocks: the bounding box of the
// segment, grown by the margin. Computed without branches, so that the CPU layer's loop over a row of
// pixels vectorises; a pixel without a usable depth is computed on the slab's near depth instead and
// marked not `valid`.
struct DepthSegment {
    Vec3f a;            // start (grid units)
    Vec3f inv_ab;       // 1 / (b - a) per axis; 0 on an axis the segment does not move along (to 1e-30 voxels)
    float margin;       // voxels the blocks' boxes grow by
    Vec3i first, last;  // candidate blocks
    bool valid;         // the pixel's depth lies in the slab: it needs blocks
    bool outside;       // valid, but the segment leaves the addressable range
};

VF_HOST_DEVICE inline DepthSegment depthSegmentOfPixel(const DepthSegmentFrame& f, int x, int y) {
    const Intrinsics& in = f.intrinsics;
    const float depth = f.depth[x + y * in.width];
    DepthSegment s;
    s.valid = depth >= f.min_depth_m && depth <= f.max_depth_m;  // also rejects 0 and NaN
    const float d = s.valid ? depth : f.min_depth_m;
    // A comparison, not fmaxf (which GCC does not vectorise); d is no NaN.
    const float z0 = d - f.mu_m > f.near_m ? d - f.mu_m : f.near_m, z1 = d + f.mu_m;
    const Vec3f ray{(float(x) - in.cx) / in.fx, (float(y) - in.cy) / in.fy, 1.f};  // z = 1
    const Vec3f a = transformPoint(f.T_grid_camera, ray * z0);
    const Vec3f b = transformPoint(f.T_grid_camera, ray * z1);
    bool addressable = true;
    for (int k = 0; k < 3; ++k)
        addressable = addressable && fabsf(a[k]) < kAddressableVoxelRange && fabsf(b[k]) < kAddressableVoxelRange;
    s.outside = s.valid && !addressable;
    // Half a pixel at the far end is the widest the footprint gets along the segment.
    s.margin = f.margin_voxels_per_m * z1 + kSegmentMarginExtraVoxels;
    s.a = a;
    // Reciprocals once per pixel: the slab tests below would otherwise divide twice per candidate block
    // per axis. Their one-ulp difference to a quotient is far inside the hundredth of a voxel that
    // kSegmentMarginExtraVoxels adds.
    const Vec3f ab = b - a;
    for (int k = 0; k < 3; ++k) {
        s.inv_ab[k] = fabsf(ab[k]) >= 1e-30f ? 1.f / ab[k] : 0.f;
        // Clamped into int range, so that a segment beyond the addressable range converts without
        // overflow (it visits no candidates: `outside` is all it reports).
        const float range = 2.f * kAddressableVoxelRange;
        float lo = (a[k] < b[k] ? a[k] : b[k]) - s.margin, hi = (a[k] < b[k] ? b[k] : a[k]) + s.margin;
        lo = lo > -range ? (lo < range ? lo : range) : -range;
        hi = hi > -range ? (hi < range ? hi : range) : -range;
        // Block c covers voxel centres [8c, 8c + 7].
        s.first[k] = int(ceilf((lo - float(kBlockSide - 1)) / float(kBlockSide)));
        s.last[k] = int(floorf(hi / float(kBlockSide)));
    }
    return s;
}

// Calls visit(Vec3i block) once for every block a depth segment needs (see above): each candidate is
// kept when the segment meets its grown box (slab test). A segment beyond the addressable range
// visits one non-addressable block instead.
template <class Visit>
VF_HOST_DEVICE inline void forEachBlockOnSegment(const DepthSegment& s, Visit& visit) {
    if (!s.valid) return;
    if (s.outside) {
        const Vec3i outside{kMaxBlockCoordinate + 1, kMaxBlockCoordinate + 1, kMaxBlockCoordinate + 1};
        visit(outside);
        return;
    }
    // The part of the segment (t in [0, 1]) inside the grown box of block c along axis k narrows
    // [t_in, t_out]; each axis's part is taken where its loop moves to the next block. (Minimum and
    // maximum are exact, so the order in which the axes narrow the range changes no result.)
    auto narrow = [&](int k, int c, float& t_in, float& t_out) {
        const float lo = float(c * kBlockSide) - s.margin, hi = float(c * kBlockSide + kBlockSide - 1) + s.margin;
        if (s.inv_ab[k] == 0.f) {
            if (s.a[k] < lo || s.a[k] > hi) t_out = -1.f;
            return;
        }
        float t_lo = (lo - s.a[k]) * s.inv_ab[k], t_hi = (hi - s.a[k]) * s.inv_ab[k];
        if (t_lo > t_hi) {
            const float swap = t_lo;
            t_lo = t_hi;
            t_hi = swap;
        }
        // Comparisons, not fminf/fmaxf (library calls on the host); no value is NaN.
        t_in = t_lo > t_in ? t_lo : t_in;
        t_out = t_hi < t_out ? t_hi : t_out;
    };
    for (int bz = s.first.z; bz <= s.last.z; ++bz) {
        float z_in = 0.f, z_out = 1.f;
        narrow(2, bz, z_in, z_out);
        if (!(z_in <= z_out)) continue;
        for (int by = s.first.y; by <= s.last.y; ++by) {
            float y_in = z_in, y_out = z_out;
            narrow(1, by, y_in, y_out);
            if (!(y_in <= y_out)) continue;
            for (int bx = s.first.x; bx <= s.last.x; ++bx) {
                float t_in = y_in, t_out = y_out;
                narrow(0, bx, t_in, t_out);
                if (t_in <= t_out) visit(Vec3i{bx, by, bz});
            }
        }
    }
}

// Every block pixel (x, y) needs (see above), one pixel at a time.
template <class Visit>
VF_HOST_DEVICE inline void forEachBlockOnDepthSegment(const DepthSegmentFrame& f, int x, int y, Visit& visit) {
    forEachBlockOnSegment(depthSegmentOfPixel(f, x, y), visit);
}

// Appends to the missing list are counted up to here and no further, so that the count cannot overflow
// an int however many blocks a frame asks for (a voxel size far below the depth's resolution asks for
// billions). Concurrent appends may pass it by one per thread in flight, far below the 2^20 margin.
constexpr int kMaxCountedAppends = 0x7fffffff - (1 << 20);

// What stage 1 does with each block a pixel needs: the block is marked seen when the hash has it, or
// its key is appended to the missing list (every block outside the storable coordinates as
// kOutOfRangeBlockKey). Appends beyond the list's capacity are counted but not stored (the caller
// repeats the pass).
struct MarkOrListBlock {
    HashTableView table;
    std::uint8_t* entry_visibility;
    std::uint64_t* missing;
    int* missing_count;  // appends attempted (may exceed the capacity; saturates at max_counted_appends)
    int missing_capacity;
    int max_counted_appends;

    VF_HOST_DEVICE void operator()(Vec3i block) const {
        const int entry = blockIsAddressable(block) ? findHashEntry(table, block) : -1;
        if (entry >= 0) {
            racingStore(&entry_visibility[entry], kEntrySeenThisFrame);
            return;
        }
        if (racingLoad(missing_count) >= max_counted_appends) return;
        const int slot = atomicAddInt(missing_count, 1);
        if (slot < missing_capacity) missing[slot] = blockKey(block);
    }
};

// ---- Stage 1 as the GPU runs it: a team per tile ----

// The blocks a team has handled for its tile, in its shared memory: an open-addressing set of block
// keys (4 KB). A 16 x 16 pixel tile needs some tens of blocks at 5 mm voxels and not many more than
// a hundred at 2 mm, so the set stays at most a quarter full.
constexpr int kTileBlockSetSlots = 512;  // a power of two
constexpr int kTileBlockSetProbes =
    32;  // beyond this many taken slots a block is handled again (a repeat, never a miss)
constexpr std::uint64_t kNoBlockKey = std::uint64_t(1) << 63;  // neither a block's key nor kOutOfRangeBlockKey
struct TileBlockSet {
    std::uint64_t keys[kTileBlockSetSlots];
};

// True for the one call per tile that first brings `key` (any thread of the team): that caller
// handles the block; also true when the set is too full around the key's slot to tell.
VF_HOST_DEVICE inline bool firstInTile(TileBlockSet& set, std::uint64_t key) {
    const unsigned hash = unsigned(key ^ (key >> 17) ^ (key >> 34)) * 2654435761u;
    for (int probe = 0; probe < kTileBlockSetProbes; ++probe) {
        std::uint64_t* slot = &set.keys[(hash + unsigned(probe)) & unsigned(kTileBlockSetSlots - 1)];
        std::uint64_t seen = racingLoad(slot);
        if (seen == kNoBlockKey) seen = atomicCasU64(slot, kNoBlockKey, key);
        if (seen == kNoBlockKey) return true;  // claimed by this call
        if (seen == key) return false;
    }
    return true;
}

// Allocation stage 1 for the GPU (TDevice::parallelForTeams<TileBlockSet>): item t is the t-th tile of
// kMarkTileSide x kMarkTileSide pixels (row-major), its team's threads take its pixels in turn and
// share the set of blocks the tile has handled, so that each block is looked up and appended once per
// tile, as the CPU's wide elements do. With a pixel per thread and nothing shared, every pixel
// appended every missing block it needed: more appends than the list's first size, so the first
// frame's pass ran twice, and where the list overflowed its bound the keys it kept depended on the
// order of the atomics, and with them the table. Tiles of 16 x 16 pixels keep a few teams on every
// multiprocessor at 640 x 480 (1200 tiles).
constexpr int kMarkTileSide = 16;
struct MarkBlocksForPixelTeams {
    DepthSegmentFrame frame;  // depth on the layer's device
    MarkOrListBlock handle;

    VF_HOST_DEVICE int tilesPerRow() const { return (frame.intrinsics.width + kMarkTileSide - 1) / kMarkTileSide; }
    VF_HOST_DEVICE int itemCount() const {
        return tilesPerRow() * ((frame.intrinsics.height + kMarkTileSide - 1) / kMarkTileSide);
    }
    VF_HOST_DEVICE void operator()(Team team, int item, TileBlockSet& set) const {
        for (int k = team.rank; k < kTileBlockSetSlots; k += team.size) set.keys[k] = kNoBlockKey;
        team.sync();
        const int x0 = (item % tilesPerRow()) * kMarkTileSide, y0 = (item / tilesPerRow()) * kMarkTileSide;
        auto mark = [&](Vec3i block) {
            if (firstInTile(set, blockKey(block))) handle(block);
        };
        for (int p = team.rank; p < kMarkTileSide * kMarkTileSide; p += team.size) {
            const int x = x0 + p % kMarkTileSide, y = y0 + p / kMarkTileSide;
            if (x < frame.intrinsics.width && y < frame.intrinsics.height)
                forEachBlockOnDepthSegment(frame, x, y, mark);
        }
    }
};

// Allocation stage 3, per hash entry: blocks seen this frame become visible; blocks visible before stay
// while their box is in the view frustum; everything else (and every entry without a block) is not.
struct UpdateEntryVisibility {
    HashTableState table;
    BlockProjection projection;  // the live view
    VF_HOST_DEVICE void operator()(int i) const {
        const std::uint8_t mark = table.entry_visibility[i];
        if (mark == kEntryNotVisible) return;
        const HashEntry& e = table.entries[i];
        bool visible = e.ptr >= 0;
        if (visible && mark == kEntryVisible) {
            Vec2f lo, hi;
            float z_min, z_max;
            visible = projectBlockBox({e.pos.x, e.pos.y, e.pos.z}, 0.5f, projection, lo, hi, z_min, z_max);
        }
        table.entry_visibility[i] = visible ? kEntryVisible : kEntryNotVisible;
    }
};

// Selects the visible entries (for the launchers' selectIndices).
struct EntryIsVisible {
    const std::uint8_t* entry_visibility;
    VF_HOST_DEVICE bool operator()(int i) const { return entry_visibility[i] == kEntryVisible; }
};

// Blocks come off the free stack with old contents (removal does not clear them): element i resets
// voxel i % 512 of block ptrs[i / 512].
template <class TVoxel>
struct ResetVoxelBlocks {
    TVoxel* voxels;
    const int* ptrs;
    VF_HOST_DEVICE void operator()(int i) const {
        voxels[(long long)ptrs[i / kBlockVoxelCount] * kBlockVoxelCount + i % kBlockVoxelCount] = TVoxel::initial();
    }
};

// Block removal: a block holds information while one of its voxels has a depth observation.
template <class TVoxel>
VF_HOST_DEVICE inline bool blockIsEmpty(const TVoxel* block_voxels) {
    for (int i = 0; i < kBlockVoxelCount; ++i)
        if (block_voxels[i].w_depth > 0) return false;
    return true;
}

// Per entry: remove[i] = 1 for an active block that is empty (a block whose stored copy waits to be
// merged in holds information even while its voxels are empty).
template <class TVoxel>
struct MarkEmptyBlocks {
    const HashEntry* entries;
    const int* stored_slot;
    const TVoxel* voxels;
    std::uint8_t* remove;
    VF_HOST_DEVICE void operator()(int i) const {
        const int ptr = entries[i].ptr;
        remove[i] =
            ptr >= 0 && stored_slot[i] == kNoStoredCopy && blockIsEmpty(voxels + (long long)ptr * kBlockVoxelCount) ? 1
                                                                                                                    : 0;
    }
};

}  // namespace voxfuse
