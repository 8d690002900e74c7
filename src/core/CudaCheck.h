#pragma once
// Every CUDA runtime call goes through VF_CUDA_CHECK: a failure throws DeviceError naming the call,
// the file and line, and CUDA's own message.

#include <cuda_runtime.h>

#include <string>

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
        throw DeviceError(std::string(call) + " failed at " + file + ":" + std::to_string(line) + ": " + cudaGetErrorString(status));
}

// Ceiling division for grid sizes.
inline unsigned int blocksFor(int n, int block) { return unsigned((n + block - 1) / block); }

}  // namespace voxfuse::cuda

#define VF_CUDA_CHECK(call) ::voxfuse::cuda::check((call), #call, __FILE__, __LINE__)
// After a kernel launch: catches bad launch configurations at once, and faults at the next sync.
#define VF_CUDA_CHECK_LAUNCH() VF_CUDA_CHECK(cudaGetLastError())
