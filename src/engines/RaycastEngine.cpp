// Host-side helpers of the raycast engine.

#include "voxfuse/engines/RaycastEngine.h"

#include "voxfuse/core/Error.h"

namespace voxfuse {

void raycastDepth(const RenderState& rs, Image<float>& depth_m) {
    if (!rs.points_world.memory().isCurrent(Device::CPU))
        throw DeviceError(
            "raycastDepth reads the raycast in host memory: bring it up to date first (RenderState::updateHost)");
    depth_m.resize(rs.points_world.size());
    const Mat4f T_camera_world = rigidInverse(rs.T_world_camera);
    const Vec4f* points = rs.points_world.host();
    float* out = depth_m.host();
    for (std::size_t i = 0; i < depth_m.pixelCount(); ++i)
        out[i] = points[i].w > 0.f ? transformPoint(T_camera_world, points[i].xyz()).z : 0.f;
}

}  // namespace voxfuse
