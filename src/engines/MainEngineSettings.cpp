// MainEngineSettings: validation with remedies, the memory the index needs and the block ceiling that
// follows the machine, the map file's settings, and the names of voxel and index types.

#include "MainEngineSettings.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "VoxelTypeDispatch.h"
#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/mapping/PoseGraph.h"
#include "voxfuse/objects/VoxelBlockHash.h"

namespace voxfuse {

namespace {

// Voxel coordinates of a dense volume stay within this of the origin: there a float still holds every
// integer coordinate exactly, and offset + size never overflows an int.
constexpr int kMaxDenseCoordinate = 1 << 24;

// The widest truncation band accepted, in voxels (see validation in create()).
constexpr float kMaxMuInVoxels = 64.f;

std::string gib(double bytes) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f GiB", bytes / double(1ull << 30));
    return text;
}

// What the kernel says it could give this process now, in bytes: MemAvailable, plus free swap with
// `with_swap` (Linux); 0 when unknown.
double availableHostBytes(bool with_swap) {
    std::ifstream meminfo("/proc/meminfo");
    std::string key;
    double kb = 0.0, total_kb = 0.0;
    int found = 0;
    while (meminfo >> key >> kb) {
        if (key == "MemAvailable:" || (with_swap && key == "SwapFree:")) {
            total_kb += kb;
            ++found;
        }
        meminfo.ignore(256, '\n');
    }
    return found > 0 ? total_kb * 1024.0 : 0.0;
}

std::size_t voxelBytes(VoxelType type) {
    return visitVoxelType(type, [](auto tag) { return sizeof(typename decltype(tag)::Voxel); });
}

// The memory the index needs before the first frame: the dense array, or the hash's tables (its
// voxel blocks grow with the scene).
double indexBytes(const MainEngineSettings& s) {
    if (s.index_type == IndexType::Dense)
        return double(s.dense_size.x) * double(s.dense_size.y) * double(s.dense_size.z) *
               double(voxelBytes(s.voxel_type));
    return double(VoxelBlockHash::tableBytesFor(s.hash));
}

std::string indexDescription(const MainEngineSettings& s) {
    if (s.index_type == IndexType::Dense)
        return "the dense volume of " + std::to_string(s.dense_size.x) + "x" + std::to_string(s.dense_size.y) + "x" +
               std::to_string(s.dense_size.z) + " '" + toString(s.voxel_type) + "' voxels";
    return "the hash table of " +
           std::to_string((long long)s.hash.bucket_count * s.hash.entries_per_bucket + s.hash.excess_entry_count) +
           " entries";
}

void validateDepthRange(const SceneParams& p) {
    if (!(p.view_frustum_min_m >= 0.f && std::isfinite(p.view_frustum_min_m) && std::isfinite(p.view_frustum_max_m) &&
          p.view_frustum_max_m > p.view_frustum_min_m))
        throw ConfigError("the depth range needs 0 <= minimum < maximum, both finite (--min-depth, --max-depth); got " +
                          std::to_string(p.view_frustum_min_m) + " .. " + std::to_string(p.view_frustum_max_m) + " m");
}

void validateDenseVolume(const MainEngineSettings& s) {
    for (int a = 0; a < 3; ++a) {
        const long long lo = s.dense_offset[a], hi = lo + s.dense_size[a];
        if (s.dense_size[a] <= 0)
            throw ConfigError("dense volume size must be positive (--volume-size), got " +
                              std::to_string(s.dense_size[a]) + " on axis " + "xyz"[a]);
        if (lo < -kMaxDenseCoordinate || hi > kMaxDenseCoordinate)
            throw ConfigError(std::string("the dense volume must lie within +-") + std::to_string(kMaxDenseCoordinate) +
                              " voxels of the origin (--volume-offset, --volume-size); on axis " + "xyz"[a] +
                              " it spans " + std::to_string(lo) + " .. " + std::to_string(hi));
    }
}

}  // namespace

int automaticMaxBlockCount(Device device, std::size_t voxel_bytes, const VoxelBlockHashSettings& hash,
                           double available_bytes) {
    constexpr int kDesignBlocks = 1 << 18, kMostBlocks = 1 << 22;
    if (!(available_bytes > 0.0)) return kDesignBlocks;
    // The tables as large as they may grow: as many blocks as they then have entries.
    const VoxelBlockHashSettings largest = VoxelBlockHash::fullyGrown(hash);
    const long long entries = (long long)largest.bucket_count * largest.entries_per_bucket + largest.excess_entry_count;
    // Per block: its voxels (twice on the GPU, whose growth holds the old array and the new one at
    // once; the host array grows in place), and its places in the free stack and the visible list.
    const double voxel_copies = device == Device::CUDA ? 2.0 : 1.0;
    const double block_bytes = voxel_copies * double(voxel_bytes) * kBlockVoxelCount + 2.0 * sizeof(int);
    VoxelBlockHashSettings tables = largest;
    tables.max_block_count = 0;
    const double for_blocks = 0.75 * available_bytes - double(VoxelBlockHash::tableBytesFor(tables));
    // In steps of 2^16 blocks, so that runs on one machine choose the same ceiling (map headers hold it)
    // while the free memory drifts a little between them.
    constexpr long long kStep = 1 << 16;
    const long long by_memory = for_blocks > 0.0 ? (long long)(for_blocks / block_bytes) : 0;
    const long long stepped = by_memory >= kStep ? by_memory / kStep * kStep : by_memory;
    return int(std::max<long long>(1, std::min<long long>({entries, kMostBlocks, stepped})));
}

MainEngineSettings checkedMainEngineSettings(const MainEngineSettings& requested, const RGBDCalib& calib) {
    MainEngineSettings s = requested;
    if (s.index_type == IndexType::Hash && s.hash.max_block_count == kAutomaticBlockCount)
        s.hash.max_block_count = automaticMaxBlockCount(
            s.device, voxelBytes(s.voxel_type), s.hash,
            s.device == Device::CUDA ? double(device_memory::freeDeviceBytes()) : availableHostBytes(false));
    if (!calib.depth.valid()) throw ConfigError("the depth camera calibration is missing or invalid");
    if (!(s.scene.voxel_size_m > 0.f && std::isfinite(s.scene.voxel_size_m)) ||
        !(s.scene.mu_m > s.scene.voxel_size_m && std::isfinite(s.scene.mu_m)))
        throw ConfigError("need voxel size > 0 and mu > voxel size, both finite (got voxel " +
                          std::to_string(s.scene.voxel_size_m) + " m, mu " + std::to_string(s.scene.mu_m) + " m)");
    // Every pixel allocates and integrates the blocks within mu of its depth: a band of hundreds of
    // voxels (mu = 8 m at 1 cm) made a frame take seconds to minutes. Usual bands are 2-8 voxels.
    if (s.scene.mu_m > kMaxMuInVoxels * s.scene.voxel_size_m)
        throw ConfigError("mu " + std::to_string(s.scene.mu_m) + " m is more than " +
                          std::to_string(int(kMaxMuInVoxels)) + " voxels of " + std::to_string(s.scene.voxel_size_m) +
                          " m (a truncation band is usually 2-8 voxels)");
    if (s.scene.max_weight < 1 || s.scene.max_weight > 255) throw ConfigError("max weight must be in 1..255");
    validateDepthRange(s.scene);
    if (!(s.depth_gap_tolerance >= 0.f && s.depth_gap_tolerance <= 0.5f))
        throw ConfigError(
            "the depth gap tolerance is a fraction of the depth in [0, 0.5], 0 to keep every gap "
            "(--depth-gap-tolerance); got " +
            std::to_string(s.depth_gap_tolerance));
    if (s.index_type == IndexType::Dense) validateDenseVolume(s);
    if (s.swap.enabled && s.index_type != IndexType::Hash)
        throw ConfigError("swapping needs the hash index (--index hash)");
    if (s.swap.enabled && s.swap.blocks_per_frame < 1) throw ConfigError("swapping moves at least one block per frame");
    if (s.submaps.enabled && !poseGraphAvailable())
        throw ConfigError(
            "submaps need pose graph optimisation, which this build lacks (install libceres-dev and "
            "rebuild)");
    if (s.submaps.enabled && s.index_type != IndexType::Hash)
        throw ConfigError("submaps need the hash index (--index hash)");
    if (s.submaps.enabled &&
        (!(s.submaps.max_distance_m > 0.f) || !std::isfinite(s.submaps.max_distance_m) || s.submaps.overlap_frames < 0))
        throw ConfigError("submaps need a positive, finite distance and angle and overlap frames >= 0");
    if (s.tracking_raycast_downsample != 1 && s.tracking_raycast_downsample != 2 && s.tracking_raycast_downsample != 4)
        throw ConfigError("the tracking raycast's downsampling must be 1, 2 or 4 (got " +
                          std::to_string(s.tracking_raycast_downsample) + ")");
    if (s.device == Device::CUDA && !device_memory::cudaAvailable())
        throw DeviceError("CUDA was requested but is not usable: " + device_memory::cudaDescription());
    // Said before the allocation, which would otherwise fail as a bare std::bad_alloc (or, with the
    // kernel's overcommit, kill the process when the memory is first touched).
    const double needed = indexBytes(s), available = availableHostBytes(true);
    if (s.device == Device::CPU && available > 0.0 && needed > available)
        throw ConfigError(indexDescription(s) + " needs " + gib(needed) + " of memory; this machine has " +
                          gib(available) + " available: " + indexRemedy(s));
    return s;
}

std::string indexRemedy(const MainEngineSettings& s) {
    return s.index_type == IndexType::Dense
               ? "use a smaller --volume-size, or the hash index (--index hash), whose memory follows the scene"
               : "use fewer --hash-buckets / --hash-excess";
}

std::string indexMemoryNeed(const MainEngineSettings& s) {
    return indexDescription(s) + " needs " + gib(indexBytes(s));
}

MainEngineSettings settingsForMap(const MapFileInfo& info, MainEngineSettings base) {
    base.voxel_type = parseVoxelType(info.voxel_type);
    base.index_type = info.hash ? IndexType::Hash : IndexType::Dense;
    if (info.hash) {
        // The table as it was saved, growing as far as `base`'s would (the file does not hold that).
        const int max_buckets = base.hash.max_bucket_count;
        base.hash = info.hash_settings;
        base.hash.max_bucket_count = max_buckets;
    } else {
        base.dense_offset = info.dense_offset;
        base.dense_size = info.dense_size;
    }
    base.scene.voxel_size_m = info.scene.voxel_size_m;
    base.scene.mu_m = info.scene.mu_m;
    if (info.submap_count > 0) base.submaps.enabled = true;  // a single map loads with submaps on or off
    return base;
}

VoxelType parseVoxelType(const std::string& name) {
    std::string names;
    for (const VoxelType type : kVoxelTypes) {
        if (name == toString(type)) return type;
        names += std::string(names.empty() ? "" : ", ") + toString(type);
    }
    throw ConfigError("unknown voxel type '" + name + "' (expected one of " + names + ")");
}

const char* toString(VoxelType type) {
    return visitVoxelType(type, [](auto tag) { return decltype(tag)::Voxel::name; });
}

bool voxelTypeHasColor(VoxelType type) {
    return visitVoxelType(type, [](auto tag) { return decltype(tag)::Voxel::hasColor; });
}

bool voxelTypeHasLabels(VoxelType type) {
    return visitVoxelType(type, [](auto tag) { return decltype(tag)::Voxel::hasLabel; });
}

IndexType parseIndexType(const std::string& name) {
    if (name == "dense") return IndexType::Dense;
    if (name == "hash") return IndexType::Hash;
    throw ConfigError("unknown index type '" + name + "' (expected dense or hash)");
}

const char* toString(IndexType type) { return type == IndexType::Dense ? "dense" : "hash"; }

const char* toString(TrackingStatus status) {
    return status == TrackingStatus::Tracking ? "tracking" : status == TrackingStatus::Lost ? "lost" : "relocalised";
}

}  // namespace voxfuse
