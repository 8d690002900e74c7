#pragma once
// Depth tracking (section 4.1 of the InfiniTAM report): point-to-plane ICP of the current depth frame
// against the model raycast, coarse to fine. The host side (src/engines/DepthTracker.cpp) builds the
// frame pyramid and runs Gauss-Newton on SE(3); the device layer (src/cpu/DepthTracker_CPU.cpp) sums
// the normal equations of one iteration over the pixels of a level, calling pointToPlaneTerm() from
// shared/DepthTracker.h. The same host loop runs the "ren" refinement (a robust kernel at full
// resolution) and "rgbd" (photometric terms from ColorTracker.h added to the system).

#include <memory>

#include "voxfuse/core/Image.h"
#include "voxfuse/engines/Tracker.h"
#include "voxfuse/shared/DepthTracker.h"
#include "voxfuse/shared/NormalEquations.h"
#include "voxfuse/shared/RobustKernel.h"

namespace voxfuse {

// One pyramid level of the current depth frame.
struct DepthFrameLevel {
    Intrinsics intrinsics;  // the depth camera at this level's resolution
    Image<float> depth;     // metres, 0 = invalid
    Image<Vec4f> vertices;  // camera coordinates, w = 1 where valid
    Image<Vec4f> normals;   // camera coordinates, w = 1 where valid
};

class DepthTrackerKernels {
public:
    virtual ~DepthTrackerKernels() = default;
    // The point-to-plane normal equations of every vertex of `level` against `model`, each term
    // weighted by robustWeight(kernel, residual, kernel_scale_m); terms of weight 0 are left out.
    virtual NormalEquations<double> accumulate(const DepthFrameLevel& level, const RenderState& model, const DepthTermParams& params,
                                               RobustKernel kernel, float kernel_scale_m) = 0;
};

namespace cpu {
std::unique_ptr<DepthTrackerKernels> makeDepthTrackerKernels();
}

// The icp, ren and rgbd trackers.
std::unique_ptr<Tracker> makeDepthTracker(const TrackerSettings& settings, Device device);

}  // namespace voxfuse
