#pragma once
// A swapped map in one piece on the host, for meshes, clouds and map files.

#include <algorithm>
#include <vector>

#include "voxfuse/objects/GlobalCache.h"
#include "voxfuse/objects/Scene.h"
#include "voxfuse/objects/VoxelBlockHash.h"
#include "voxfuse/shared/Swapping.h"  // mergeStoredVoxel

namespace voxfuse {

// The whole map of `scene` in host memory: its active blocks, the stored ones read from `cache`, and the
// copies still waiting merged in as swapping in would merge them; in a voxel array as large as the map
// needs (it may exceed the active budget, so the copy's ceiling is 2^22 blocks, not `hash`'s).
template <class TVoxel>
Scene<TVoxel, VoxelBlockHash> wholeMapOnHost(const Scene<TVoxel, VoxelBlockHash>& scene, const GlobalCache& cache,
                                             const VoxelBlockHashSettings& hash) {
    Scene<TVoxel, VoxelBlockHash> host = scene.copyTo(Device::CPU);
    if (host.index().storedBlocks() == 0) return host;
    VoxelBlockHashSettings unbounded = hash;
    unbounded.max_block_count = 1 << 22;
    Scene<TVoxel, VoxelBlockHash> whole(scene.params(), VoxelBlockHash(unbounded), Device::CPU);
    whole.reserveVoxelBlocks(host.index().blocksInUse() + host.index().storedBlocks());
    const VoxelBlockHash& from = host.index();
    std::vector<TVoxel> stored(kBlockVoxelCount);
    for (int i = 0; i < from.entryCount(); ++i) {
        const HashEntry& e = from.entry(i);
        if (e.ptr < 0 && e.ptr != kEntrySwappedOut) continue;
        int entry;
        whole.index().insert({e.pos.x, e.pos.y, e.pos.z}, &entry);
        TVoxel* block = whole.voxels().host() + std::size_t(whole.index().entry(entry).ptr) * kBlockVoxelCount;
        if (e.ptr >= 0)
            std::copy_n(host.voxels().host() + std::size_t(e.ptr) * kBlockVoxelCount, kBlockVoxelCount, block);
        else
            std::fill_n(block, kBlockVoxelCount, TVoxel::initial());
        const int slot = from.storedSlots()[i];
        if (slot == kNoStoredCopy) continue;
        cache.read(slot, stored.data());
        for (int v = 0; v < kBlockVoxelCount; ++v)
            mergeStoredVoxel(block[v], stored[std::size_t(v)], scene.params().max_weight);
    }
    return whole;
}

}  // namespace voxfuse
