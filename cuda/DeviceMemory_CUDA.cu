// device_memory on the CUDA runtime. A CUDA build still runs on machines without a GPU: every entry
// point but cudaAvailable() then throws DeviceError.

#include "CudaCheck.h"
#include "voxfuse/core/DeviceMemory.h"

namespace voxfuse {

const char* deviceName(Device d) { return d == Device::CPU ? "cpu" : "cuda"; }

namespace device_memory {

bool builtWithCuda() { return true; }

bool cudaAvailable() {
    int count = 0;
    if (cudaGetDeviceCount(&count) != cudaSuccess) {
        cudaGetLastError();  // clear the sticky "no driver / no device" status
        return false;
    }
    return count > 0;
}

std::string cudaDescription() {
    int count = 0;
    const cudaError_t status = cudaGetDeviceCount(&count);
    if (status != cudaSuccess) {
        cudaGetLastError();
        return std::string("no usable CUDA device (") + cudaGetErrorString(status) + ")";
    }
    if (count == 0) return "no CUDA device";
    cudaDeviceProp prop{};
    int device = 0;
    if (cudaGetDevice(&device) != cudaSuccess || cudaGetDeviceProperties(&prop, device) != cudaSuccess) return "CUDA device (unknown)";
    return std::string(prop.name) + " (sm_" + std::to_string(prop.major) + std::to_string(prop.minor) + ", " +
           std::to_string(prop.totalGlobalMem >> 20) + " MiB)";
}

void* allocate(std::size_t bytes) {
    void* p = nullptr;
    VF_CUDA_CHECK(cudaMalloc(&p, bytes));
    return p;
}

void release(void* ptr) noexcept { cudaFree(ptr); }

void copyHostToDevice(void* dst, const void* src, std::size_t bytes) { VF_CUDA_CHECK(cudaMemcpy(dst, src, bytes, cudaMemcpyHostToDevice)); }
void copyDeviceToHost(void* dst, const void* src, std::size_t bytes) { VF_CUDA_CHECK(cudaMemcpy(dst, src, bytes, cudaMemcpyDeviceToHost)); }
void copyDeviceToDevice(void* dst, const void* src, std::size_t bytes) { VF_CUDA_CHECK(cudaMemcpy(dst, src, bytes, cudaMemcpyDeviceToDevice)); }
void fill(void* dst, int byte_value, std::size_t bytes) { VF_CUDA_CHECK(cudaMemset(dst, byte_value, bytes)); }

}  // namespace device_memory
}  // namespace voxfuse
