#pragma once
// Swapping in the frame loop (the InfiniTAM report, section 5; docs/DESIGN_NOTES.md, "Swapping"): with
// SwapSettings::enabled, on the hash only, the voxel array holds the blocks near the view and the global
// cache (host memory or a swap file) the rest. Stored copies of the blocks a frame needs come back
// before it is fused; blocks that left the view go to the cache after. The main engine owns one.

#include <memory>
#include <type_traits>

#include "StageClock.h"
#include "SwappedMapOnHost.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/engines/SwappingEngine.h"
#include "voxfuse/objects/GlobalCache.h"
#include "voxfuse/objects/Scene.h"

namespace voxfuse {

template <class TVoxel, class TIndex>
class MapSwapping {
    static constexpr bool kHash = std::is_same<TIndex, VoxelBlockHash>::value;

public:
    explicit MapSwapping(const MainEngineSettings& settings) : swap_(settings.swap), hash_(settings.hash) {
        if constexpr (kHash) {
            if (swap_.enabled) {
                engine_ = makeSwappingEngine<TVoxel>(settings.device);
                cache_ = newCache();
            }
        }
    }

    bool enabled() const { return engine_ != nullptr; }
    GlobalCache* cache() const { return cache_.get(); }  // null without swapping
    // An empty cache of this map's kind (null without swapping): a new map, or one a map file fills.
    std::unique_ptr<GlobalCache> newCache() const {
        if (!enabled()) return nullptr;
        return std::make_unique<GlobalCache>(sizeof(TVoxel) * kBlockVoxelCount, swap_.swap_file);
    }
    void setCache(std::unique_ptr<GlobalCache> cache) {
        if (enabled()) cache_ = std::move(cache);
    }

    // Before fusion: the stored copies of the blocks the frame needs come back.
    void swapIn(Scene<TVoxel, TIndex>& scene, AllocationStats& stats, StageClock& clock) {
        if (!enabled()) return;
        if constexpr (kHash)
            stats.blocks_swapped_in_this_frame = engine_->swapIn(scene, *cache_, swap_.blocks_per_frame);
        clock.stageDone("swap_in");
    }
    // After fusion: blocks that left the view go to the cache.
    void swapOut(Scene<TVoxel, TIndex>& scene, AllocationStats& stats, StageClock& clock) {
        if (!enabled()) return;
        if constexpr (kHash)
            stats.blocks_swapped_out_this_frame = engine_->swapOut(scene, *cache_, swap_.blocks_per_frame);
        clock.stageDone("swap_out");
    }

    bool hasStoredBlocks(const Scene<TVoxel, TIndex>& scene) const {
        if constexpr (kHash) return scene.index().storedBlocks() > 0;
        return false;
    }
    // The whole map in host memory, stored blocks and waiting copies included (SwappedMapOnHost.h).
    Scene<TVoxel, TIndex> completeHostCopy(const Scene<TVoxel, TIndex>& scene) const {
        if constexpr (kHash)
            if (hasStoredBlocks(scene)) return wholeMapOnHost(scene, *cache_, hash_);
        return scene.copyTo(Device::CPU);
    }

private:
    SwapSettings swap_;
    VoxelBlockHashSettings hash_;
    std::unique_ptr<SwappingEngine<TVoxel>> engine_;  // with SwapSettings::enabled (hash only)
    std::unique_ptr<GlobalCache> cache_;
};

}  // namespace voxfuse
