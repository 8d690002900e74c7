#pragma once
// The device layers of the trackers, written once for both devices: the per-pixel sums of one
// Gauss-Newton iteration (DepthTrackerKernels, ColorTrackerKernels) as templates on the device type,
// instantiated by src/cpu/TrackerKernels_CPU.cpp and cuda/TrackerKernels_CUDA.cu. The host side of the
// trackers (src/engines/DepthTracker.cpp, ColorTracker.cpp) is device-agnostic: it solves the 6x6
// system each sum returns. Per-pixel terms: shared/DepthTrackerTerms.h and shared/ColorTrackerTerms.h.

#include <memory>

#include "core/DeviceScratch.h"
#include "engines/DeviceImages.h"
#include "engines/LowLevelEngine_Impl.h"  // outputOn
#include "voxfuse/engines/ColorTracker.h"
#include "voxfuse/engines/DepthTracker.h"

namespace voxfuse {

template <class TDevice>
class DepthTrackerKernelsOn final : public DepthTrackerKernels {
    static constexpr Device kDevice = TDevice::kind;

public:
    NormalEquations<double> accumulate(const DepthFrameLevel& level, const RenderState& model,
                                       const DepthTermParams& params, RobustKernel kernel,
                                       float kernel_scale_m) override {
        const PointToPlaneTerms terms{imageOn(kDevice, level.vertices, vertices_),
                                      imageOn(kDevice, level.normals, normals_),
                                      imageOn(kDevice, model.points_world, model_points_),
                                      imageOn(kDevice, model.normals_world, model_normals_), params};
        return TDevice::sumNormalEquations(int(level.vertices.pixelCount()), terms, kernel, kernel_scale_m, scratch_);
    }

private:
    DeviceScratch scratch_{kDevice};
    MemoryBlock<Vec4f> vertices_, normals_, model_points_, model_normals_;  // staging for images of the other device
};

template <class TDevice>
class ColorTrackerKernelsOn final : public ColorTrackerKernels {
    static constexpr Device kDevice = TDevice::kind;

public:
    void intensityFromRgb(const Image<Vec4u8>& rgb, Image<float>& intensity) override {
        const Vec4u8* in = imageOn(kDevice, rgb, rgb_);
        TDevice::parallelFor(int(rgb.pixelCount()), IntensityPixels{in, outputOn(kDevice, intensity, rgb.size())});
    }

    void downsampleIntensity(const Image<float>& in, Image<float>& out) override {
        const Vec2i size{in.width() / 2, in.height() / 2};
        const float* src = imageOn(kDevice, in, floats_);
        TDevice::parallelFor(size.x * size.y,
                             DownsampleIntensityPixels{src, in.size(), size.x, outputOn(kDevice, out, size)});
    }

    void sobelGradient(const Image<float>& intensity, Image<Vec2f>& gradient) override {
        const float* src = imageOn(kDevice, intensity, floats_);
        TDevice::parallelFor(int(intensity.pixelCount()),
                             SobelPixels{src, intensity.size(), outputOn(kDevice, gradient, intensity.size())});
    }

    void colorModelPoints(const RenderState& model, int step, const Image<float>& intensity, const Intrinsics& rgb,
                          const Mat4f& T_rgb_world, Image<ColorPoint>& points) override {
        const Vec2i size{model.points_world.width() / step, model.points_world.height() / step};
        const ColorModelPoints body{imageOn(kDevice, model.points_world, model_points_),
                                    model.points_world.width(),
                                    step,
                                    size.x,
                                    imageOn(kDevice, intensity, floats_),
                                    intensity.size(),
                                    T_rgb_world,
                                    rgb,
                                    outputOn(kDevice, points, size)};
        TDevice::parallelFor(size.x * size.y, body);
    }

    void farFieldPoints(const Image<float>& far_depth, const Intrinsics& depth_camera, int step,
                        const Mat4f& T_world_camera, const ColorFrameLevel& color, const Mat4f& T_rgb_world,
                        Image<ColorPoint>& points, Image<float>& gradient_sq) override {
        const Vec2i size{far_depth.width() / step, far_depth.height() / step};
        const FarFieldPoints body{imageOn(kDevice, far_depth, far_depth_),
                                  far_depth.size(),
                                  step,
                                  size.x,
                                  depth_camera,
                                  T_world_camera,
                                  imageOn(kDevice, color.intensity, floats_),
                                  imageOn(kDevice, color.gradient, gradients_),
                                  color.intensity.size(),
                                  T_rgb_world,
                                  color.intrinsics,
                                  outputOn(kDevice, points, size),
                                  outputOn(kDevice, gradient_sq, size)};
        TDevice::parallelFor(size.x * size.y, body);
    }

    void unhiddenFarFieldPoints(const Image<ColorPoint>& points, const Image<float>& depth,
                                const Intrinsics& depth_camera, const Mat4f& T_camera_world,
                                Image<ColorPoint>& unhidden) override {
        const UnhiddenFarFieldPoints body{imageOn(kDevice, points, points_),
                                          imageOn(kDevice, depth, far_depth_),
                                          depth.size(),
                                          T_camera_world,
                                          depth_camera,
                                          outputOn(kDevice, unhidden, points.size())};
        TDevice::parallelFor(int(points.pixelCount()), body);
    }

    NormalEquations<double> accumulate(const Image<ColorPoint>& points, const ColorFrameLevel& level,
                                       const ColorTermParams& params, RobustKernel kernel,
                                       float kernel_scale) override {
        const PhotometricTerms terms{imageOn(kDevice, points, points_), imageOn(kDevice, level.intensity, floats_),
                                     imageOn(kDevice, level.gradient, gradients_), level.intensity.size(), params};
        return TDevice::sumNormalEquations(int(points.pixelCount()), terms, kernel, kernel_scale, scratch_);
    }

    int countColoredPoints(const Image<ColorPoint>& points) override {
        return TDevice::countIf(int(points.pixelCount()), PointIsColored{imageOn(kDevice, points, points_)}, scratch_);
    }

private:
    DeviceScratch scratch_{kDevice};
    // Staging for images of the other device.
    MemoryBlock<Vec4u8> rgb_;
    MemoryBlock<float> floats_;
    MemoryBlock<Vec2f> gradients_;
    MemoryBlock<Vec4f> model_points_;
    MemoryBlock<ColorPoint> points_;
    MemoryBlock<float> far_depth_;
};

}  // namespace voxfuse
