#pragma once
// Every CUDA runtime call goes through VF_CUDA_CHECK: a failure throws DeviceError naming the call,
// the file and line, and CUDA's own message.

#include <cuda_runtime.h>
#include <cxxabi.h>

#include <cstdlib>
#include <string>
#include <typeinfo>

#include "voxfuse/core/Error.h"

namespace voxfuse::cuda {

// Whether a call succeeded. The runtime also keeps a failure as its "last error", which the next
// launch check would report against an innocent kernel: a failure is taken off it here (errors that
// break the context stay). Alone for the calls whose failure is handled where they are made (a
// fallback, a description) or cannot be (a release).
inline bool succeeded(cudaError_t status) {
    if (status == cudaSuccess) return true;
    cudaGetLastError();
    return false;
}

inline void check(cudaError_t status, const char* call, const char* file, int line) {
    if (!succeeded(status))
        throw DeviceError(std::string(call) + " failed at " + file + ":" + std::to_string(line) + ": " +
                          cudaGetErrorString(status));
}

// VOXFUSE_CUDA_SYNC=1 makes every launch wait for its kernel (read once per process): a fault is then
// reported at the launch of the kernel that caused it, not at the next copy or synchronisation,
// which may be many kernels later. For debugging; it serialises the host with the GPU.
bool syncAfterEveryLaunch();

// After a kernel launch: a bad launch configuration at once; with VOXFUSE_CUDA_SYNC=1 also the
// kernel's own fault. Otherwise a fault surfaces at the next call that waits for the GPU.
// `kernel` names what ran (the loop body's type, as typeid gives it), for the message. The name is
// made only on failure: launches are many per frame.
inline std::string launchDescription(const char* kernel) {
    std::string what = "launch of kernel";
    if (!kernel) return what;
    int status = -1;
    char* readable = abi::__cxa_demangle(kernel, nullptr, nullptr, &status);
    what += std::string(" ") + (status == 0 && readable ? readable : kernel);
    std::free(readable);
    return what;
}
inline void checkLaunch(const char* file, int line, const char* kernel = nullptr) {
    cudaError_t status = cudaGetLastError();
    bool waited = false;
    if (status == cudaSuccess && syncAfterEveryLaunch()) {
        status = cudaDeviceSynchronize();
        waited = true;
    }
    if (status != cudaSuccess)
        check(status, (launchDescription(kernel) + (waited ? " (VOXFUSE_CUDA_SYNC=1: run to its end)" : "")).c_str(),
              file, line);
}

// Ceiling division for grid sizes.
inline unsigned int blocksFor(int n, int block) { return unsigned((n + block - 1) / block); }

}  // namespace voxfuse::cuda

#define VF_CUDA_CHECK(call) ::voxfuse::cuda::check((call), #call, __FILE__, __LINE__)
#define VF_CUDA_CHECK_LAUNCH() ::voxfuse::cuda::checkLaunch(__FILE__, __LINE__)
#define VF_CUDA_CHECK_LAUNCH_OF(Body) ::voxfuse::cuda::checkLaunch(__FILE__, __LINE__, typeid(Body).name())
