#pragma once
// Image processing before tracking and integration. Images are processed where the engine's device
// says (host copies for the CPU engine).

#include <cstdint>
#include <memory>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/core/Image.h"
#include "voxfuse/objects/RGBDCalib.h"

namespace voxfuse {

struct BilateralFilterParams {
    int radius_px = 2;            // 5x5 window
    float sigma_space_px = 2.5f;
    float sigma_depth_m = 0.03f;  // depth differences well above this are treated as edges
};

class LowLevelEngine {
public:
    virtual ~LowLevelEngine() = default;
    // Raw samples to metres through the calibration; samples outside [min_m, max_m] become 0.
    virtual void convertDepthToMetres(const Image<std::uint16_t>& raw, const DisparityCalib& calib, float fx_depth,
                                      float min_m, float max_m, Image<float>& depth_m) = 0;
    virtual void bilateralFilterDepth(const Image<float>& in, Image<float>& out, const BilateralFilterParams& params) = 0;
    // Half resolution; see downsampleDepthPixel for how holes and edges are handled.
    virtual void downsampleDepth(const Image<float>& in, Image<float>& out, float max_diff_m) = 0;
    virtual void computeVertexMap(const Image<float>& depth, const Intrinsics& intrinsics, Image<Vec4f>& vertices) = 0;
    virtual void computeNormalMap(const Image<Vec4f>& vertices, Image<Vec4f>& normals, float max_edge_m) = 0;
};

namespace cpu {
std::unique_ptr<LowLevelEngine> makeLowLevelEngine();
}

// The engine of `device`. Low-level processing has no CUDA layer yet: Device::CUDA throws DeviceError.
inline std::unique_ptr<LowLevelEngine> makeLowLevelEngine(Device device) {
    if (device != Device::CPU) throw DeviceError("low-level image processing has no CUDA layer yet: use Device::CPU");
    return cpu::makeLowLevelEngine();
}

}  // namespace voxfuse
