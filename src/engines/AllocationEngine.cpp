// Host-side logic of the allocation engine shared by its device layers.

#include "voxfuse/engines/AllocationEngine.h"

#include <cmath>

#include "voxfuse/engines/IntegrationEngine.h"

namespace voxfuse {

DepthSegmentFrame makeDepthSegmentFrame(const SceneParams& params, const View& view, const Mat4f& T_world_camera) {
    DepthSegmentFrame f{};
    // Scaling the rigid transform's rows by 1 / voxel size maps camera metres straight to grid units.
    const float inv_voxel = 1.f / params.voxel_size_m;
    f.T_grid_camera = T_world_camera;
    for (int i = 0; i < 12; ++i) f.T_grid_camera.m[i] *= inv_voxel;
    f.intrinsics = view.calib.depth;
    f.depth = view.depth.host();
    f.mu_m = params.mu_m;
    f.min_depth_m = params.view_frustum_min_m;
    f.max_depth_m = params.view_frustum_max_m;
    f.near_m = kIntegrationNearM;
    const Intrinsics& in = view.calib.depth;
    f.margin_voxels_per_m = 0.5f * std::sqrt(1.f / (in.fx * in.fx) + 1.f / (in.fy * in.fy)) * inv_voxel;
    return f;
}

}  // namespace voxfuse
