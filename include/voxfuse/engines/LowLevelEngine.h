#pragma once
// Image processing before tracking and integration. Stages: src/engines/LowLevelEngine_Impl.h, run
// by src/cpu/LowLevelEngine_CPU.cpp and cuda/LowLevelEngine_CUDA.cu; per-pixel work in shared/LowLevel.h.

#include <cstdint>
#include <memory>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/core/Image.h"
#include "voxfuse/objects/RGBDCalib.h"

namespace voxfuse {

struct BilateralFilterParams {
    int radius_px = 2;  // 5x5 window
    float sigma_space_px = 2.5f;
    float sigma_depth_m = 0.03f;  // depth differences well above this are treated as edges
};

class LowLevelEngine {
public:
    virtual ~LowLevelEngine() = default;
    // Images are read and written on the engine's device (input copies made when they are current
    // elsewhere; outputs sized and written there).
    //
    // Raw samples to metres through the calibration; samples outside [min_m, max_m] become 0. Pixels
    // without a measurement between two agreeing neighbours are filled when gap_tolerance > 0 (see
    // ConvertDepthPixels in shared/LowLevel.h).
    virtual void convertDepthToMetres(const Image<std::uint16_t>& raw, const DisparityCalib& calib, float fx_depth,
                                      float min_m, float max_m, float gap_tolerance, Image<float>& depth_m) = 0;
    virtual void bilateralFilterDepth(const Image<float>& in, Image<float>& out,
                                      const BilateralFilterParams& params) = 0;
    // Half resolution; see downsampleDepthPixel for how holes and edges are handled.
    virtual void downsampleDepth(const Image<float>& in, Image<float>& out, float max_diff_m) = 0;
    virtual void computeVertexMap(const Image<float>& depth, const Intrinsics& intrinsics, Image<Vec4f>& vertices) = 0;
    virtual void computeNormalMap(const Image<Vec4f>& vertices, Image<Vec4f>& normals, float max_edge_m) = 0;
    // The camera-frame points and normals (as computeVertexMap's and computeNormalMap's) of the pixels
    // of every pixel_step-th row and column of `depth`, packed: element (gx, gy) of both outputs, of
    // size ceil(width / pixel_step) x ceil(height / pixel_step), is pixel (gx, gy) * pixel_step. What a
    // tracker level reads, without a vertex map of every pixel.
    virtual void computeGridPointsAndNormals(const Image<float>& depth, const Intrinsics& intrinsics, float max_edge_m,
                                             int pixel_step, Image<Vec4f>& vertices, Image<Vec4f>& normals) = 0;
    virtual void copyDepth(const Image<float>& in, Image<float>& out) = 0;
    // In place: depths beyond max_depth_m become 0 (no measurement); infinity keeps them all.
    virtual void dropDepthBeyond(Image<float>& depth, float max_depth_m) = 0;
    // Pixels with depth (> 0), points with w > 0. With `pixel_step` > 1, only the pixels of every
    // pixel_step-th row and column are counted (the pixels a subsampled tracker level uses).
    virtual int countValidDepth(const Image<float>& depth, int pixel_step = 1) = 0;
    virtual int countValidPoints(const Image<Vec4f>& points) = 0;
    // Averages over a `cells` grid laid over the frame (shared/LowLevel.h: CellAverages), as
    // {mean, valid pixels} per cell: depth over the pixels that have one,
    // intensity (r + g + b) over all. The relocaliser's codes read these; on the GPU only they come down.
    virtual void averageDepthCells(const Image<float>& depth_m, Vec2i cells, Image<Vec2f>& mean_and_count) = 0;
    virtual void averageIntensityCells(const Image<Vec4u8>& rgb, Vec2i cells, Image<Vec2f>& mean_and_count) = 0;
    virtual Device device() const = 0;
};

namespace cpu {
std::unique_ptr<LowLevelEngine> makeLowLevelEngine();
}
namespace cuda {
std::unique_ptr<LowLevelEngine> makeLowLevelEngine();
}

// The engine of `device`; DeviceError in a build without CUDA.
inline std::unique_ptr<LowLevelEngine> makeLowLevelEngine(Device device) {
    return device == Device::CPU ? cpu::makeLowLevelEngine() : cuda::makeLowLevelEngine();
}

}  // namespace voxfuse
