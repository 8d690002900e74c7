// The _voxfuse extension module; `voxfuse/__init__.py` re-exports it as the voxfuse package.

#include "Bindings.h"
#include "voxfuse/core/DeviceMemory.h"

PYBIND11_MODULE(_voxfuse, m) {
    m.doc() = "VoxFuse: dense 3D reconstruction from RGB-D frames (the C++ library's bindings).";
    using namespace voxfuse::python;
    bindErrors(m);
    bindCalibration(m);
    bindSources(m);
    bindMapOutputs(m);
    bindPipeline(m);
    bindTrajectory(m);
    m.def("cuda_available", &voxfuse::device_memory::cudaAvailable,
          "True when this build has CUDA and a GPU is usable, so that Pipeline(device='cuda') can run.");
    m.def("built_with_cuda", &voxfuse::device_memory::builtWithCuda, "True when this build has the CUDA engines.");
}
