#pragma once
// Colour tracking (section 4.1 of the InfiniTAM report): model surface points with intensities are
// projected into the current colour image and the photometric error is minimised with
// Levenberg-Marquardt, coarse to fine over an intensity pyramid, on every color_point_step-th pixel.
//
// Where the model's intensities come from: InfiniTAM reads them from the voxels; VoxFuse colours the
// raycast points with the PREVIOUS frame's colour image (projected at the previous frame's tracked
// pose, remembered by the tracker at the end of each track() call). It works with every voxel type
// (colorless ones included) and samples at image resolution instead of voxel resolution; the price
// is frame-to-frame photometric drift, which the depth terms of the rgbd tracker keep in check.
//
// Host side: src/engines/ColorTracker.cpp (LM loop) and PhotometricFrames (pyramids, model colours);
// device layers: src/engines/TrackerKernels_Impl.h, run by src/cpu/TrackerKernels_CPU.cpp and
// cuda/TrackerKernels_CUDA.cu; per-point terms: shared/ColorTrackerTerms.h.

#include <memory>

#include "voxfuse/core/Image.h"
#include "voxfuse/engines/Tracker.h"
#include "voxfuse/shared/ColorTrackerTerms.h"
#include "voxfuse/shared/NormalEquations.h"
#include "voxfuse/shared/RobustKernel.h"

namespace voxfuse {

// One pyramid level of the current colour frame.
struct ColorFrameLevel {
    Intrinsics intrinsics;   // the colour camera at this level's resolution
    Image<float> intensity;  // [0, 1]
    Image<Vec2f> gradient;   // Sobel, intensity per pixel
};

class ColorTrackerKernels {
public:
    virtual ~ColorTrackerKernels() = default;
    virtual void intensityFromRgb(const Image<Vec4u8>& rgb, Image<float>& intensity) = 0;
    virtual void downsampleIntensity(const Image<float>& in, Image<float>& out) = 0;
    virtual void sobelGradient(const Image<float>& intensity, Image<Vec2f>& gradient) = 0;
    // The model points at every `step`-th pixel of the raycast (points image of size model / step),
    // coloured from `intensity`, an image taken by a colour camera `rgb` at T_rgb_world.
    virtual void colorModelPoints(const RenderState& model, int step, const Image<float>& intensity,
                                  const Intrinsics& rgb, const Mat4f& T_rgb_world, Image<ColorPoint>& points) = 0;
    // The far-field points of every `step`-th pixel of `far_depth` (points and gradient_sq images of
    // size far_depth / step; see shared farFieldPoint): a keyframe of depth camera `depth_camera` at
    // T_world_camera, coloured by its colour pyramid's finest level `color` (camera at T_rgb_world).
    virtual void farFieldPoints(const Image<float>& far_depth, const Intrinsics& depth_camera, int step,
                                const Mat4f& T_world_camera, const ColorFrameLevel& color, const Mat4f& T_rgb_world,
                                Image<ColorPoint>& points, Image<float>& gradient_sq) = 0;
    // `points` as a frame with depths `depth` (within the map's range) at T_camera_world sees them: a
    // point outside its view or behind a surface it measured loses its colour (unhiddenFarFieldPoint).
    virtual void unhiddenFarFieldPoints(const Image<ColorPoint>& points, const Image<float>& depth,
                                        const Intrinsics& depth_camera, const Mat4f& T_camera_world,
                                        Image<ColorPoint>& unhidden) = 0;
    // The photometric normal equations of every coloured point against `level`.
    virtual NormalEquations<double> accumulate(const Image<ColorPoint>& points, const ColorFrameLevel& level,
                                               const ColorTermParams& params, RobustKernel kernel,
                                               float kernel_scale) = 0;
    // Points that found an intensity.
    virtual int countColoredPoints(const Image<ColorPoint>& points) = 0;
};

namespace cpu {
std::unique_ptr<ColorTrackerKernels> makeColorTrackerKernels();
}
namespace cuda {
std::unique_ptr<ColorTrackerKernels> makeColorTrackerKernels();
}
// The device layer of `device`; DeviceError in a build without CUDA.
inline std::unique_ptr<ColorTrackerKernels> makeColorTrackerKernels(Device device) {
    return device == Device::CPU ? cpu::makeColorTrackerKernels() : cuda::makeColorTrackerKernels();
}

// The colour-only tracker.
std::unique_ptr<Tracker> makeColorTracker(const TrackerSettings& settings, Device device);

}  // namespace voxfuse
