// The CUDA engine factories in a build without CUDA: asking for one is a clear error. One stub per
// engine of VF_FOR_EACH_CUDA_ENGINE and voxel/index pair of VF_FOR_EACH_ENGINE_PAIR, per voxel type
// for swapping (hash only), and the untemplated low-level engine and tracker layers.

#include <string>

#include "voxfuse/core/Error.h"
#include "voxfuse/engines/AllocationEngine.h"
#include "voxfuse/engines/ColorTracker.h"
#include "voxfuse/engines/DepthTracker.h"
#include "voxfuse/engines/EnginePairs.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/engines/LowLevelEngine.h"
#include "voxfuse/engines/MeshingEngine.h"
#include "voxfuse/engines/RaycastEngine.h"
#include "voxfuse/engines/SwappingEngine.h"

namespace voxfuse::cuda {
namespace {
[[noreturn]] void noCuda(const char* engine) {
    throw DeviceError(std::string("the CUDA ") + engine +
                      " is not in this VoxFuse build (rebuild with -DVOXFUSE_CUDA=ON)");
}
}  // namespace

#define VF_INSTANTIATE_STUB(Engine, TVoxel, TIndex) \
    template std::unique_ptr<Engine<TVoxel, TIndex>> make##Engine<TVoxel, TIndex>();
#define VF_STUB(Engine)                                      \
    template <class TVoxel, class TIndex>                    \
    std::unique_ptr<Engine<TVoxel, TIndex>> make##Engine() { \
        noCuda(#Engine);                                     \
    }                                                        \
    VF_FOR_EACH_ENGINE_PAIR_WITH(VF_INSTANTIATE_STUB, Engine)
VF_FOR_EACH_CUDA_ENGINE(VF_STUB)
#undef VF_STUB
#undef VF_INSTANTIATE_STUB

template <class TVoxel>
std::unique_ptr<SwappingEngine<TVoxel>> makeSwappingEngine() {
    noCuda("SwappingEngine");
}
#define VF_INSTANTIATE_SWAPPING(TVoxel) template std::unique_ptr<SwappingEngine<TVoxel>> makeSwappingEngine<TVoxel>();
VF_FOR_EACH_VOXEL(VF_INSTANTIATE_SWAPPING)
#undef VF_INSTANTIATE_SWAPPING

std::unique_ptr<LowLevelEngine> makeLowLevelEngine() { noCuda("LowLevelEngine"); }
std::unique_ptr<DepthTrackerKernels> makeDepthTrackerKernels() { noCuda("DepthTracker"); }
std::unique_ptr<ColorTrackerKernels> makeColorTrackerKernels() { noCuda("ColorTracker"); }

}  // namespace voxfuse::cuda
