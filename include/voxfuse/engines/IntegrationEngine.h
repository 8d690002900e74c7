#pragma once
// Fusing a depth (and colour, and class) frame into the scene. Stages: src/engines/IntegrationEngine_Impl.h,
// run by src/cpu/IntegrationEngine_CPU.cpp and cuda/IntegrationEngine_CUDA.cu; every voxel update is
// integrateVoxel() from shared/Integration.h. An engine works on scenes of its own device.

#include <memory>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/objects/PlainVoxelArray.h"
#include "voxfuse/objects/Scene.h"
#include "voxfuse/objects/View.h"
#include "voxfuse/shared/Integration.h"

namespace voxfuse {

template <class TVoxel, class TIndex>
class IntegrationEngine {
public:
    virtual ~IntegrationEngine() = default;
    // Fuses `view` seen from the depth camera pose T_world_camera.
    virtual void integrate(Scene<TVoxel, TIndex>& scene, const View& view, const Mat4f& T_world_camera) = 0;
    // Forgets everything: every voxel back to TVoxel::initial().
    virtual void resetScene(Scene<TVoxel, TIndex>& scene) = 0;
};

// ---- Host-side logic shared by the device layers ----

// The per-frame constants of integrateVoxel(); `depth`, `rgb` and `labels` point to where the loop
// reads them (host or device copies of the view's images), `integration_number` is the scene's
// Scene::takeIntegrationNumber() for this frame (the label fusion's seed).
IntegrationFrame makeIntegrationFrame(const SceneParams& params, const View& view, const Mat4f& T_world_camera,
                                      const float* depth, const Vec4u8* rgb, const ClassId* labels,
                                      std::uint32_t integration_number);

// Voxels closer to the camera than this are never updated (their projection is ill-conditioned).
constexpr float kIntegrationNearM = 0.01f;

// The box of dense-grid voxels (array coordinates, inclusive lo, exclusive hi) that can receive an
// update from a frame of `camera` whose farthest usable depth is `max_depth_m`: the view frustum from
// the camera to mu behind that depth (returned as far_m), clipped to the array. False when the box is
// empty (no usable depth, or the frustum misses the array).
bool denseIntegrationBox(const PlainVoxelArray::Data& index, const SceneParams& params, const Intrinsics& camera,
                         const Mat4f& T_world_camera, float max_depth_m, Vec3i& lo, Vec3i& hi, float& far_m);

namespace cpu {
template <class TVoxel, class TIndex>
std::unique_ptr<IntegrationEngine<TVoxel, TIndex>> makeIntegrationEngine();
}
namespace cuda {
template <class TVoxel, class TIndex>
std::unique_ptr<IntegrationEngine<TVoxel, TIndex>> makeIntegrationEngine();
}

template <class TVoxel, class TIndex>
std::unique_ptr<IntegrationEngine<TVoxel, TIndex>> makeIntegrationEngine(Device device) {
    return device == Device::CPU ? cpu::makeIntegrationEngine<TVoxel, TIndex>()
                                 : cuda::makeIntegrationEngine<TVoxel, TIndex>();
}

}  // namespace voxfuse
