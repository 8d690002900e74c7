#pragma once
// Allocation stage 1 for one depth pixel (section 4.2 of the InfiniTAM report): which voxel blocks the
// pixel's measurement needs. Plus the emptiness test of block removal.
//
// Integration gives a voxel a signed distance below +1 when it projects into a pixel with depth d and
// its own depth z lies in [d - mu, d + mu). Those voxels lie in the pixel's footprint between the
// depths d - mu and d + mu: within half a pixel (sideways) of the segment of the pixel's centre ray
// between those depths. Stage 1 samples that segment and visits every block holding a voxel centre
// within (half a pixel + half a sample spacing) of a sample, so no block such a voxel lies in is missed.

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/Intrinsics.h"
#include "voxfuse/objects/VoxelBlockHash.h"

namespace voxfuse {

// The per-frame constants of stage 1 (trivially copyable).
struct DepthSegmentFrame {
    Mat4f T_grid_camera;       // depth camera coordinates (metres) -> voxel grid coordinates
    Intrinsics intrinsics;     // of the depth camera
    const float* depth;        // metres, 0 = invalid
    float mu_m;                // truncation band
    float min_depth_m, max_depth_m;  // depth samples outside are ignored (as integration does)
    float near_m;              // segments start no closer than this
    float margin_voxels_per_m; // half a pixel's diagonal footprint per metre of depth, in voxels
    float step_voxels;         // spacing of the samples along the segment
};

// Segments beyond this many voxels from the origin need blocks no entry can store (int16 coordinates).
constexpr float kAddressableVoxelRange = float((kMaxBlockCoordinate + 1) * kBlockSide);

// Calls visit(Vec3i block) for every block pixel (x, y) needs (see above); a block may be visited more
// than once. A segment beyond the addressable range visits one non-addressable block instead.
template <class Visit>
VF_HOST_DEVICE inline void forEachBlockOnDepthSegment(const DepthSegmentFrame& f, int x, int y, Visit& visit) {
    const Intrinsics& in = f.intrinsics;
    const float d = f.depth[x + y * in.width];
    if (!(d >= f.min_depth_m && d <= f.max_depth_m)) return;  // also rejects 0 and NaN
    const float z0 = fmaxf(d - f.mu_m, f.near_m), z1 = d + f.mu_m;
    const Vec3f ray{(float(x) - in.cx) / in.fx, (float(y) - in.cy) / in.fy, 1.f};  // z = 1
    const Vec3f a = transformPoint(f.T_grid_camera, ray * z0);
    const Vec3f b = transformPoint(f.T_grid_camera, ray * z1);
    for (int k = 0; k < 3; ++k)
        if (!(fabsf(a[k]) < kAddressableVoxelRange && fabsf(b[k]) < kAddressableVoxelRange)) {
            const Vec3i outside{kMaxBlockCoordinate + 1, kMaxBlockCoordinate + 1, kMaxBlockCoordinate + 1};
            visit(outside);
            return;
        }
    const Vec3f ab = b - a;
    const int steps = 1 + int(length(ab) / f.step_voxels);
    const float margin = f.margin_voxels_per_m * z1 + 0.5f * length(ab) / float(steps) + 1e-3f;

    // Consecutive samples mostly cover the same blocks: skip those visited for the last few samples.
    Vec3i recent[8];
    int recent_count = 0, recent_next = 0;
    for (int i = 0; i <= steps; ++i) {
        const Vec3f p = a + ab * (float(i) / float(steps));
        // Blocks of the voxel centres (integer grid points) within `margin` of p along every axis.
        const Vec3i lo{int(ceilf(p.x - margin)) >> 3, int(ceilf(p.y - margin)) >> 3, int(ceilf(p.z - margin)) >> 3};
        const Vec3i hi{int(floorf(p.x + margin)) >> 3, int(floorf(p.y + margin)) >> 3, int(floorf(p.z + margin)) >> 3};
        for (int bz = lo.z; bz <= hi.z; ++bz)
            for (int by = lo.y; by <= hi.y; ++by)
                for (int bx = lo.x; bx <= hi.x; ++bx) {
                    const Vec3i block{bx, by, bz};
                    bool seen = false;
                    for (int r = 0; r < recent_count; ++r) seen = seen || recent[r] == block;
                    if (seen) continue;
                    recent[recent_next] = block;
                    recent_next = (recent_next + 1) & 7;
                    recent_count = recent_count < 8 ? recent_count + 1 : 8;
                    visit(block);
                }
    }
}

// Block removal: a block holds information while one of its voxels has a depth observation.
template <class TVoxel>
VF_HOST_DEVICE inline bool blockIsEmpty(const TVoxel* block_voxels) {
    for (int i = 0; i < kBlockVoxelCount; ++i)
        if (block_voxels[i].w_depth > 0) return false;
    return true;
}

}  // namespace voxfuse
