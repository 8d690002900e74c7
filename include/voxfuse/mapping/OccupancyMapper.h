#pragma once
// An OctoMap occupancy map (free / occupied / unknown) built beside the TSDF from the same depth
// frames and camera poses, on its own thread: inserting rays into an octree on the CPU is far slower
// than fusion, so frames and pixels are subsampled (Algorithm 5 of the KinectFusion/OctoMap thesis
// cited in docs/DESIGN_NOTES.md) and a full queue drops frames instead of stalling the fusion loop.
//
// The octree lives behind a pimpl, so users of this header need no OctoMap headers. In a build
// without OctoMap (VOXFUSE_WITH_OCTOMAP undefined) the constructor throws ConfigError.

#include <cstdint>
#include <memory>
#include <string>

#include "voxfuse/core/Image.h"
#include "voxfuse/core/Math.h"
#include "voxfuse/objects/Intrinsics.h"

namespace voxfuse {

struct OccupancySettings {
    float resolution_m = 0.05f;  // leaf cell edge
    int frame_step = 1;          // map every Nth submitted frame
    int pixel_step = 4;          // use every Nth pixel in x and in y
    float max_range_m = 4.0f;    // longer beams clear free space up to here but mark nothing occupied; <= 0: no limit
    int queue_capacity = 4;      // frames waiting for the worker; more are dropped
};

struct OccupancyStats {
    std::int64_t frames_submitted = 0;  // every submit() call
    std::int64_t frames_skipped = 0;    // left out by frame_step
    std::int64_t frames_dropped = 0;    // queue full
    std::int64_t frames_inserted = 0;   // in the octree
    std::int64_t points_inserted = 0;   // beam endpoints of the inserted frames
    double insert_ms = 0.0;             // worker time spent in insertPointCloud
};

enum class Occupancy { Unknown, Free, Occupied };

class OccupancyMapper {
public:
    // Starts the worker thread. Throws ConfigError for settings out of range.
    explicit OccupancyMapper(const OccupancySettings& settings);
    // Discards frames still queued and joins the worker (call finish() first to keep them).
    ~OccupancyMapper();
    OccupancyMapper(const OccupancyMapper&) = delete;
    OccupancyMapper& operator=(const OccupancyMapper&) = delete;

    // Queues the frame's subsampled points; never waits for the worker. depth_m: metres, 0 or
    // non-finite = no measurement. Returns false only when the queue was full and the frame was
    // dropped; a frame skipped by frame_step returns true. Throws Error after finish().
    bool submit(const Image<float>& depth_m, const Intrinsics& intrinsics, const Mat4f& T_world_camera);
    // Inserts every queued frame and stops the worker. Idempotent, from any thread. Rethrows what
    // stopped the worker early (OctoMap's std::bad_alloc on a map too large for memory).
    void finish();
    // finish(), then writes the pruned maximum-likelihood map as a binary OctoMap (.bt).
    // Throws IoError when the file cannot be written.
    void write(const std::string& path);

    // The state of the leaf cell holding p_world; safe to call while mapping.
    Occupancy occupancyAt(Vec3f p_world) const;
    OccupancyStats stats() const;
    const OccupancySettings& settings() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace voxfuse
