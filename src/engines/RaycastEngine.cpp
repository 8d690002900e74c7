// Host-side helpers of the raycast engine.

#include "voxfuse/engines/RaycastEngine.h"

namespace voxfuse {

void raycastDepth(const RenderState& rs, Image<float>& depth_m) {
    depth_m.resize(rs.points_world.size());
    const Mat4f T_camera_world = rigidInverse(rs.T_world_camera);
    const Vec4f* points = rs.points_world.host();
    float* out = depth_m.host();
    for (std::size_t i = 0; i < depth_m.pixelCount(); ++i)
        out[i] = points[i].w > 0.f ? transformPoint(T_camera_world, points[i].xyz()).z : 0.f;
}

}  // namespace voxfuse
