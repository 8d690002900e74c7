// Host-side logic of the integration engine shared by its CPU and CUDA layers.

#include <algorithm>
#include <cmath>

#include "voxfuse/engines/IntegrationEngine.h"

namespace voxfuse {

IntegrationFrame makeIntegrationFrame(const SceneParams& params, const View& view, const Mat4f& T_world_camera,
                                      const float* depth, const Vec4u8* rgb, const ClassId* labels,
                                      std::uint32_t integration_number) {
    IntegrationFrame f{};
    f.T_depth_world = rigidInverse(T_world_camera);
    f.depth_intrinsics = view.calib.depth;
    f.depth = depth;
    // The colour camera sees world points through depth-from-world followed by rgb-from-depth.
    f.T_rgb_world = rigidInverse(view.calib.T_depth_rgb) * f.T_depth_world;
    f.rgb = view.rgb.empty() ? nullptr : rgb;
    // Colour and label images whose size disagrees with the calibration are scaled into it.
    f.rgb_intrinsics = f.rgb ? view.colorCamera() : view.calib.rgb;
    f.labels = view.labels.empty() ? nullptr : labels;
    f.T_label_world = view.calib.labelsFromColor() ? f.T_rgb_world : f.T_depth_world;
    f.label_intrinsics = view.calib.labelCamera().resized(view.labels.width(), view.labels.height());
    f.label_update = params.label_update;
    f.label_seed = integration_number;
    f.voxel_size_m = params.voxel_size_m;
    f.mu_m = params.mu_m;
    f.max_weight = params.max_weight;
    f.min_depth_m = params.view_frustum_min_m;
    f.max_depth_m = params.view_frustum_max_m;
    f.near_m = kIntegrationNearM;
    f.stop_at_max_weight = params.stop_integrating_at_max_weight;
    const Mat4f& T = f.T_depth_world;
    const float s = params.voxel_size_m;
    f.voxel_step_x = Vec3f{T.m[0], T.m[4], T.m[8]} * s;
    f.voxel_step_y = Vec3f{T.m[1], T.m[5], T.m[9]} * s;
    f.voxel_step_z = Vec3f{T.m[2], T.m[6], T.m[10]} * s;
    return f;
}

bool denseIntegrationBox(const PlainVoxelArray::Data& index, const SceneParams& params, const Intrinsics& camera,
                         const Mat4f& T_world_camera, float max_depth_m, Vec3i& lo, Vec3i& hi, float& far_m) {
    // Voxels in front of the nearest surface are carved too (they are free space), so the slab starts
    // at the camera; it ends mu behind the farthest usable depth.
    if (!(max_depth_m > 0.f)) return false;
    far_m = max_depth_m + params.mu_m;
    const float near_m = kIntegrationNearM;

    // The eight corners of the frustum slab, in world coordinates, bound every voxel that can change.
    const Intrinsics& in = camera;
    Vec3f box_lo{INFINITY, INFINITY, INFINITY}, box_hi{-INFINITY, -INFINITY, -INFINITY};
    for (int k = 0; k < 8; ++k) {
        const float u = (k & 1) ? float(in.width) - 0.5f : -0.5f;
        const float v = (k & 2) ? float(in.height) - 0.5f : -0.5f;
        const float z = (k & 4) ? far_m : near_m;
        const Vec3f p = transformPoint(T_world_camera, in.unproject(u, v, z));
        for (int a = 0; a < 3; ++a) {
            box_lo[a] = std::min(box_lo[a], p[a]);
            box_hi[a] = std::max(box_hi[a], p[a]);
        }
    }
    for (int a = 0; a < 3; ++a) {
        const int first = int(std::floor(box_lo[a] / params.voxel_size_m)) - 1;
        const int last = int(std::ceil(box_hi[a] / params.voxel_size_m)) + 2;
        lo[a] = std::max(first, index.offset[a]) - index.offset[a];
        hi[a] = std::min(last, index.offset[a] + index.size[a]) - index.offset[a];
        if (lo[a] >= hi[a]) return false;
    }
    return true;
}

}  // namespace voxfuse
