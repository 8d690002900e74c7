#pragma once
// Raycasting the model from a viewpoint (for the tracker and for display) and rendering images from
// the result. Stages: src/engines/RaycastEngine_Impl.h, run by src/cpu/RaycastEngine_CPU.cpp and
// cuda/RaycastEngine_CUDA.cu; per-ray and per-pixel work in shared/Raycast.h and shared/Render.h.
// An engine works on scenes of its own device; its RenderState images live there too.

#include <memory>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/objects/RenderState.h"
#include "voxfuse/objects/Scene.h"
#include "voxfuse/shared/Render.h"  // RenderMode

namespace voxfuse {

// Where a raycast's normals come from.
enum class RaycastNormals {
    SdfGradient,  // central differences of the TSDF at each hit: smooth shading, valid up to silhouettes (renders)
    FromPoints    // differences of neighbouring hits in the image, as the frame's normals: a fraction of the cost (the
                  // tracker's model)
};

template <class TVoxel, class TIndex>
class RaycastEngine {
public:
    virtual ~RaycastEngine() = default;
    // Fills render_state's points and normals for every pixel of `intrinsics` seen from T_world_camera.
    // `depth_hint_m`, when given: the depth (metres) of the frame just fused from this pose, at the
    // raycast's resolution or an integer multiple of it; rays start two truncation bands in front of
    // the nearest depth in their footprint (RaycastDepthHint in shared/Raycast.h: a fraction of the
    // steps; a surface the model still holds in front of what the frame saw is not found).
    // `with_intensity`: render_state.intensity too, as renderIntensity would make it, read where the
    // rays already are (in the same pass on a hash).
    virtual void raycast(const Scene<TVoxel, TIndex>& scene, const Intrinsics& intrinsics, const Mat4f& T_world_camera,
                         RenderState& render_state, RaycastNormals normals = RaycastNormals::SdfGradient,
                         const Image<float>* depth_hint_m = nullptr, bool with_intensity = false) = 0;
    // An RGBA image of the last raycast (a raycast of this engine's device), with its host copy up to date.
    virtual void render(const Scene<TVoxel, TIndex>& scene, const RenderState& render_state, RenderMode mode,
                        Image<Vec4u8>& image) = 0;
    // The map's colours at the last raycast's hits as intensities in [0, 1], -1 where there is none
    // (RenderIntensityPixel), on the engine's device; all -1 for voxels without colour.
    virtual void renderIntensity(const Scene<TVoxel, TIndex>& scene, const RenderState& render_state,
                                 Image<float>& intensity) = 0;
};

// Depth (metres along the optical axis of the raycast camera) of each raycast pixel; 0 where nothing was hit.
void raycastDepth(const RenderState& render_state, Image<float>& depth_m);

namespace cpu {
template <class TVoxel, class TIndex>
std::unique_ptr<RaycastEngine<TVoxel, TIndex>> makeRaycastEngine();
}
namespace cuda {
template <class TVoxel, class TIndex>
std::unique_ptr<RaycastEngine<TVoxel, TIndex>> makeRaycastEngine();
}

// The engine of `device` for scenes on that device; DeviceError in a build without CUDA.
template <class TVoxel, class TIndex>
std::unique_ptr<RaycastEngine<TVoxel, TIndex>> makeRaycastEngine(Device device) {
    return device == Device::CPU ? cpu::makeRaycastEngine<TVoxel, TIndex>() : cuda::makeRaycastEngine<TVoxel, TIndex>();
}

}  // namespace voxfuse
