// CUDA layer of the trackers: src/engines/TrackerKernels_Impl.h on the CUDA launcher.

#include "core/CudaDevice.cuh"
#include "engines/TrackerKernels_Impl.h"

namespace voxfuse::cuda {

std::unique_ptr<DepthTrackerKernels> makeDepthTrackerKernels() {
    return std::make_unique<DepthTrackerKernelsOn<CudaDevice>>();
}
std::unique_ptr<ColorTrackerKernels> makeColorTrackerKernels() {
    return std::make_unique<ColorTrackerKernelsOn<CudaDevice>>();
}

}  // namespace voxfuse::cuda
