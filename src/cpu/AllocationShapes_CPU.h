#pragma once
// The CPU's own loop shape of allocation stage 1 (engines/AllocationEngine_Impl.h picks it when the
// device is not kOneThreadPerItem): a tile of pixels per element with a cache of the blocks it handled,
// and each row's depth segments computed in a loop the compiler vectorises. The per-pixel segment and
// block walk both devices share are in shared/Allocation.h.
//
// Contract: the same blocks marked seen and the same missing list (as a set) as the pixels one by one;
// tests/engines/GpuShapesOnCpuTest.cpp (GpuShapesOnCpuAllocationTest) and AllocationEngineTest hold it to that.

#include "voxfuse/shared/Allocation.h"

namespace voxfuse {

// Blocks visited recently by one loop element (direct-mapped, `Slots` a power of two): neighbouring
// pixels mostly need the same blocks, and a block looked up once need not be looked up again.
template <int Slots>
struct RecentBlocks {
    Vec3i slots[Slots];
    RecentBlocks() {
        for (int i = 0; i < Slots; ++i) slots[i] = Vec3i{-0x7fffffff, 0, 0};  // no block has x = -2^31 + 1
    }
    // True when `b` was visited already; remembers it otherwise.
    bool checkAndRemember(Vec3i b) {
        Vec3i& slot = slots[(unsigned(b.x) * 73856093u ^ unsigned(b.y) * 19349669u ^ unsigned(b.z) * 83492791u) &
                            unsigned(Slots - 1)];
        if (slot == b) return true;
        slot = b;
        return false;
    }
};

// Allocation stage 1 for a tile of `tile.x` x `tile.y` pixels (element e: tile e, row-major), for the
// CPU layer's wide elements: each block the pixels need is handled as MarkOrListBlock says. The list
// may get a block more than once. `RecentSlots` sizes the cache of blocks already handled within the
// tile: square tiles with a large cache (a block covers some 20 x 20 pixels at 1 m, so a tile looks it
// up once where a row of pixels looked it up once per row). The GPU runs MarkBlocksForPixelTeams.
template <int RecentSlots>
struct MarkBlocksForPixels {
    DepthSegmentFrame frame;  // depth on the layer's device
    HashTableView table;
    std::uint8_t* entry_visibility;
    std::uint64_t* missing;
    int* missing_count;  // appends attempted (may exceed the capacity; saturates at kMaxCountedAppends)
    int missing_capacity;
    Vec2i tile;                                    // pixels per element along x and y
    int max_counted_appends = kMaxCountedAppends;  // where the count stops (tests set less)

    int tilesPerRow() const { return (frame.intrinsics.width + tile.x - 1) / tile.x; }
    int elementCount() const { return tilesPerRow() * ((frame.intrinsics.height + tile.y - 1) / tile.y); }
    void operator()(int element) const {
        const int x0 = (element % tilesPerRow()) * tile.x, y0 = (element / tilesPerRow()) * tile.y;
        const int x1 = x0 + tile.x < frame.intrinsics.width ? x0 + tile.x : frame.intrinsics.width;
        const int y1 = y0 + tile.y < frame.intrinsics.height ? y0 + tile.y : frame.intrinsics.height;
        RecentBlocks<RecentSlots> recent;
        const MarkOrListBlock handle{table,         entry_visibility, missing,
                                     missing_count, missing_capacity, max_counted_appends};
        auto mark = [&](Vec3i block) {
            if (!recent.checkAndRemember(block)) handle(block);
        };
        // The segments of up to kSegmentRun pixels of a row first, in one loop over the pixels (which
        // vectorises: the arrays hold them field by field), then their blocks.
        constexpr int kSegmentRun = 32;
        float ax[kSegmentRun], ay[kSegmentRun], az[kSegmentRun], ix[kSegmentRun], iy[kSegmentRun], iz[kSegmentRun],
            margin[kSegmentRun];
        int fx[kSegmentRun], fy[kSegmentRun], fz[kSegmentRun], lx[kSegmentRun], ly[kSegmentRun], lz[kSegmentRun];
        int valid[kSegmentRun], outside[kSegmentRun];  // ints: one width for every field, or GCC leaves the loop scalar
        for (int y = y0; y < y1; ++y)
            for (int run = x0; run < x1; run += kSegmentRun) {
                const int n = x1 - run < kSegmentRun ? x1 - run : kSegmentRun;
                for (int i = 0; i < n; ++i) {
                    const DepthSegment s = depthSegmentOfPixel(frame, run + i, y);
                    ax[i] = s.a.x, ay[i] = s.a.y, az[i] = s.a.z;
                    ix[i] = s.inv_ab.x, iy[i] = s.inv_ab.y, iz[i] = s.inv_ab.z;
                    margin[i] = s.margin;
                    fx[i] = s.first.x, fy[i] = s.first.y, fz[i] = s.first.z;
                    lx[i] = s.last.x, ly[i] = s.last.y, lz[i] = s.last.z;
                    valid[i] = s.valid, outside[i] = s.outside;
                }
                for (int i = 0; i < n; ++i) {
                    if (!valid[i]) continue;
                    const DepthSegment s{{ax[i], ay[i], az[i]}, {ix[i], iy[i], iz[i]}, margin[i],
                                         {fx[i], fy[i], fz[i]}, {lx[i], ly[i], lz[i]}, true,
                                         outside[i] != 0};
                    forEachBlockOnSegment(s, mark);
                }
            }
    }
};

}  // namespace voxfuse
