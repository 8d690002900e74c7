// The _voxfuse extension module; `voxfuse/__init__.py` re-exports it as the voxfuse package.

#include "Bindings.h"
#include "voxfuse/core/CpuThreads.h"
#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/Version.h"

PYBIND11_MODULE(_voxfuse, m) {
    m.doc() = "VoxFuse: dense 3D reconstruction from RGB-D frames (the C++ library's bindings).";
    m.attr("__version__") = VOXFUSE_VERSION_STRING;
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
    m.def("cpu_threads", &voxfuse::cpuThreadCount,
          "How many threads the library's CPU loops run on: set_cpu_threads(n), else the environment's\n"
          "VOXFUSE_NUM_THREADS or OMP_NUM_THREADS, else the CPUs this process may use.");
    m.def("set_cpu_threads", &voxfuse::setCpuThreadCount, pybind11::arg("threads"),
          "Sets how many threads (1 to 4096) the library's CPU loops run on, from the next loop on; 0 returns\n"
          "to the default (see cpu_threads); any other number raises ConfigError. Results do not depend on it.");
}
