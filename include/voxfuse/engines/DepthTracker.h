#pragma once
// Depth tracking (section 4.1 of the InfiniTAM report): point-to-plane ICP of the current depth frame
// against the model raycast, coarse to fine. The host side (src/engines/DepthTracker.cpp) builds the
// frame pyramid and runs Gauss-Newton on SE(3); the device layers (src/engines/TrackerKernels_Impl.h,
// run by src/cpu/TrackerKernels_CPU.cpp and cuda/TrackerKernels_CUDA.cu) sum the normal equations of
// one iteration over the pixels of a level, calling pointToPlaneTerm() from shared/DepthTrackerTerms.h
// (the CPU in double per thread, the GPU in double per block: both in an order fixed by the image). The same host loop
// runs the "ren" refinement (a robust kernel at full resolution) and "rgbd" (photometric terms from ColorTracker.h
// added to the system).

#include <memory>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/Image.h"
#include "voxfuse/engines/Tracker.h"
#include "voxfuse/shared/DepthTrackerTerms.h"
#include "voxfuse/shared/NormalEquations.h"
#include "voxfuse/shared/RobustKernel.h"

namespace voxfuse {

// One pyramid level of the current depth frame.
struct DepthFrameLevel {
    Intrinsics intrinsics;  // the depth camera at this level's resolution
    Image<float> depth;     // metres, 0 = invalid
    // The pixels the level's terms come from, packed (LowLevelEngine::computeGridPointsAndNormals): with
    // a pixel step of 2, a quarter of `depth`'s pixels.
    Image<Vec4f> vertices;  // camera coordinates, w = 1 where valid
    Image<Vec4f> normals;   // camera coordinates, w = 1 where valid
};

class DepthTrackerKernels {
public:
    virtual ~DepthTrackerKernels() = default;
    // The point-to-plane normal equations of the vertices of `level` against `model`, each term
    // weighted by robustWeight(kernel, residual, kernel_scale_m); terms of weight 0 are left out.
    virtual NormalEquations<double> accumulate(const DepthFrameLevel& level, const RenderState& model,
                                               const DepthTermParams& params, RobustKernel kernel,
                                               float kernel_scale_m) = 0;
};

namespace cpu {
std::unique_ptr<DepthTrackerKernels> makeDepthTrackerKernels();
}
namespace cuda {
std::unique_ptr<DepthTrackerKernels> makeDepthTrackerKernels();
}
// The device layer of `device`; DeviceError in a build without CUDA.
inline std::unique_ptr<DepthTrackerKernels> makeDepthTrackerKernels(Device device) {
    return device == Device::CPU ? cpu::makeDepthTrackerKernels() : cuda::makeDepthTrackerKernels();
}

// The icp, ren and rgbd trackers.
std::unique_ptr<Tracker> makeDepthTracker(const TrackerSettings& settings, Device device);

}  // namespace voxfuse
