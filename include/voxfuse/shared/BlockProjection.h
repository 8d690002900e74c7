#pragma once
// Projecting one voxel block into a camera image: whether it can be seen (allocation stage 3) and which
// pixels and depths it covers (the raycast's expected depth ranges).

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/Intrinsics.h"
#include "voxfuse/objects/HashTableTypes.h"
#include "voxfuse/objects/SceneParams.h"

namespace voxfuse {

struct BlockProjection {
    Mat4f T_camera_world;
    Intrinsics intrinsics;
    float voxel_size_m;
    float near_m, far_m;  // depth slab that counts (metres along the optical axis)
};

// Projects block `block`'s box of voxel centres, grown by `margin_voxels` on every side, into the image.
// Writes the pixel bounding box [px_lo, px_hi] (unclipped) and the depth range [z_min, z_max] of the box
// clipped to [near, far]. A box that reaches in front of the near plane may project anywhere: its pixel
// box is then the whole image. False when the box lies outside the slab or the image.
VF_HOST_DEVICE inline bool projectBlockBox(Vec3i block, float margin_voxels, const BlockProjection& P, Vec2f& px_lo,
                                           Vec2f& px_hi, float& z_min, float& z_max) {
    const Vec3f lo =
        (toFloat(block) * float(kBlockSide) - Vec3f{margin_voxels, margin_voxels, margin_voxels}) * P.voxel_size_m;
    const float extent = (float(kBlockSide - 1) + 2.f * margin_voxels) * P.voxel_size_m;
    const Intrinsics& in = P.intrinsics;
    px_lo = Vec2f{1e30f, 1e30f};
    px_hi = Vec2f{-1e30f, -1e30f};
    z_min = 1e30f;
    z_max = -1e30f;
    bool in_front_of_near = false;
    for (int k = 0; k < 8; ++k) {
        const Vec3f corner = lo + Vec3f{(k & 1) ? extent : 0.f, (k & 2) ? extent : 0.f, (k & 4) ? extent : 0.f};
        const Vec3f p = transformPoint(P.T_camera_world, corner);
        z_min = fminf(z_min, p.z);
        z_max = fmaxf(z_max, p.z);
        if (p.z < P.near_m) {
            in_front_of_near = true;
            continue;
        }
        const Vec2f px = in.project(p);
        px_lo = Vec2f{fminf(px_lo.x, px.x), fminf(px_lo.y, px.y)};
        px_hi = Vec2f{fmaxf(px_hi.x, px.x), fmaxf(px_hi.y, px.y)};
    }
    if (z_max < P.near_m || z_min > P.far_m) return false;
    z_min = fmaxf(z_min, P.near_m);
    z_max = fminf(z_max, P.far_m);
    if (in_front_of_near) {
        px_lo = Vec2f{-0.5f, -0.5f};
        px_hi = Vec2f{float(in.width) - 0.5f, float(in.height) - 0.5f};
        return true;
    }
    return px_hi.x >= -0.5f && px_hi.y >= -0.5f && px_lo.x <= float(in.width) - 0.5f &&
           px_lo.y <= float(in.height) - 0.5f;
}

// The blocks a raycast from one viewpoint can read: rays march through the image within the depths of
// their ranges ([view_frustum_min_m - a voxel, view_frustum_max_m + mu], the pads the raycast gives its
// ranges), and trilinear reads and SDF-gradient normals reach two voxels around a sample. Swapping keeps
// these blocks in the voxel array, so that its raycast reads what a run without swapping reads.
struct RaycastReach {
    static constexpr float kMarginVoxels = 2.f;
    BlockProjection projection;
    bool any = false;  // no viewpoint: nothing is in reach

    VF_HOST_DEVICE bool contains(Vec3i block) const {
        if (!any) return false;
        Vec2f lo, hi;
        float z_min, z_max;
        return projectBlockBox(block, kMarginVoxels, projection, lo, hi, z_min, z_max);
    }
};

inline RaycastReach raycastReach(const SceneParams& params, const Intrinsics& intrinsics, const Mat4f& T_world_camera) {
    const float near_m = params.view_frustum_min_m - params.voxel_size_m;
    return RaycastReach{BlockProjection{rigidInverse(T_world_camera), intrinsics, params.voxel_size_m,
                                        near_m > 1e-3f ? near_m : 1e-3f, params.view_frustum_max_m + params.mu_m},
                        true};
}

}  // namespace voxfuse
