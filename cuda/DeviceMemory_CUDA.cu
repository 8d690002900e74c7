// device_memory on the CUDA runtime. A CUDA build still runs on machines without a GPU: every entry
// point but cudaAvailable() then throws DeviceError.

#include <cstring>
#include <mutex>
#include <unordered_map>

#include "core/CudaCheck.h"
#include "core/EnvironmentSwitch.h"
#include "voxfuse/core/DeviceMemory.h"

namespace voxfuse {
namespace {

// Up to 64 bytes of one element, passed to the kernel by value.
struct FillPattern {
    unsigned char bytes[64];
};

// Thread i writes element i, byte by byte: elements need not be aligned to more than their own size.
__global__ void fillPatternKernel(unsigned char* dst, FillPattern pattern, unsigned pattern_bytes, std::size_t count) {
    const std::size_t i = std::size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= count) return;
    unsigned char* element = dst + i * pattern_bytes;
    for (unsigned b = 0; b < pattern_bytes; ++b) element[b] = pattern.bytes[b];
}

// Sizes of the live allocations, for bytesInUse() and the peak (allocations are few and large).
struct AllocationLedger {
    std::mutex mutex;
    std::unordered_map<void*, std::size_t> sizes;
    std::size_t in_use = 0, peak = 0;
};
AllocationLedger& ledger() {
    static AllocationLedger l;
    return l;
}

}  // namespace

namespace cuda {
bool syncAfterEveryLaunch() {
    static const bool on = switchFromEnvironment("VOXFUSE_CUDA_SYNC");
    return on;
}
}  // namespace cuda

const char* deviceName(Device d) { return d == Device::CPU ? "cpu" : "cuda"; }

namespace device_memory {

bool builtWithCuda() { return true; }

bool cudaAvailable() {
    int count = 0;
    return cuda::succeeded(cudaGetDeviceCount(&count)) && count > 0;  // no driver or device: false
}

std::string cudaDescription() {
    int count = 0;
    const cudaError_t status = cudaGetDeviceCount(&count);
    if (!cuda::succeeded(status)) {
        // Without any driver the runtime says its version is "insufficient": say both causes.
        if (status == cudaErrorInsufficientDriver)
            return "no usable CUDA device (no NVIDIA driver found, or one older than this build's CUDA " +
                   std::to_string(CUDART_VERSION / 1000) + "." + std::to_string(CUDART_VERSION % 1000 / 10) + " runtime)";
        return std::string("no usable CUDA device (") + cudaGetErrorString(status) + ")";
    }
    if (count == 0) return "no CUDA device";
    cudaDeviceProp prop{};
    int device = 0;
    if (!cuda::succeeded(cudaGetDevice(&device)) || !cuda::succeeded(cudaGetDeviceProperties(&prop, device))) return "CUDA device (unknown)";
    return std::string(prop.name) + " (sm_" + std::to_string(prop.major) + std::to_string(prop.minor) + ", " +
           std::to_string(prop.totalGlobalMem >> 20) + " MiB)";
}

std::size_t freeDeviceBytes() {
    std::size_t free_bytes = 0, total_bytes = 0;
    // No driver or device: 0, and the caller falls back to its default.
    return cuda::succeeded(cudaMemGetInfo(&free_bytes, &total_bytes)) ? free_bytes : 0;
}

void* allocate(std::size_t bytes) {
    void* p = nullptr;
    VF_CUDA_CHECK(cudaMalloc(&p, bytes));
    AllocationLedger& l = ledger();
    const std::lock_guard<std::mutex> lock(l.mutex);
    try {
        l.sizes[p] = bytes;
    } catch (...) {
        cudaFree(p);
        throw;
    }
    l.in_use += bytes;
    if (l.in_use > l.peak) l.peak = l.in_use;
    return p;
}

void release(void* ptr) noexcept {
    if (!ptr) return;
    cuda::succeeded(cudaFree(ptr));  // nothing to do about a failure here; kept off the next check
    AllocationLedger& l = ledger();
    const std::lock_guard<std::mutex> lock(l.mutex);
    const auto it = l.sizes.find(ptr);
    if (it == l.sizes.end()) return;
    l.in_use -= it->second;
    l.sizes.erase(it);
}

std::size_t bytesInUse() {
    AllocationLedger& l = ledger();
    const std::lock_guard<std::mutex> lock(l.mutex);
    return l.in_use;
}
std::size_t peakBytesInUse() {
    AllocationLedger& l = ledger();
    const std::lock_guard<std::mutex> lock(l.mutex);
    return l.peak;
}
void resetPeakBytes() {
    AllocationLedger& l = ledger();
    const std::lock_guard<std::mutex> lock(l.mutex);
    l.peak = l.in_use;
}

void* allocatePinned(std::size_t bytes) noexcept {
    if (!cudaAvailable()) return nullptr;
    void* p = nullptr;
    return cuda::succeeded(cudaMallocHost(&p, bytes)) ? p : nullptr;
}

void releasePinned(void* ptr) noexcept {
    if (ptr) cuda::succeeded(cudaFreeHost(ptr));
}

void copyHostToDevice(void* dst, const void* src, std::size_t bytes) { VF_CUDA_CHECK(cudaMemcpy(dst, src, bytes, cudaMemcpyHostToDevice)); }
void copyDeviceToHost(void* dst, const void* src, std::size_t bytes) { VF_CUDA_CHECK(cudaMemcpy(dst, src, bytes, cudaMemcpyDeviceToHost)); }
void copyDeviceToDevice(void* dst, const void* src, std::size_t bytes) { VF_CUDA_CHECK(cudaMemcpy(dst, src, bytes, cudaMemcpyDeviceToDevice)); }
void fill(void* dst, int byte_value, std::size_t bytes) { VF_CUDA_CHECK(cudaMemset(dst, byte_value, bytes)); }

void fillPattern(void* dst, const void* pattern, std::size_t pattern_bytes, std::size_t count) {
    if (pattern_bytes == 0 || pattern_bytes > sizeof(FillPattern)) throw DeviceError("fillPattern: element size must be 1..64 bytes");
    if (count == 0) return;
    FillPattern p{};
    std::memcpy(p.bytes, pattern, pattern_bytes);
    const unsigned threads = 256;
    const std::size_t blocks = (count + threads - 1) / threads;
    fillPatternKernel<<<unsigned(blocks), threads>>>(static_cast<unsigned char*>(dst), p, unsigned(pattern_bytes), count);
    VF_CUDA_CHECK_LAUNCH();
}

void synchronize() { VF_CUDA_CHECK(cudaDeviceSynchronize()); }

void* createEvent() {
    cudaEvent_t e = nullptr;
    VF_CUDA_CHECK(cudaEventCreate(&e));
    return e;
}
void destroyEvent(void* event) noexcept {
    if (event) cuda::succeeded(cudaEventDestroy(static_cast<cudaEvent_t>(event)));
}
void recordEvent(void* event) { VF_CUDA_CHECK(cudaEventRecord(static_cast<cudaEvent_t>(event))); }
float eventElapsedMs(void* start, void* end) {
    VF_CUDA_CHECK(cudaEventSynchronize(static_cast<cudaEvent_t>(end)));
    float ms = 0.f;
    VF_CUDA_CHECK(cudaEventElapsedTime(&ms, static_cast<cudaEvent_t>(start), static_cast<cudaEvent_t>(end)));
    return ms;
}

}  // namespace device_memory
}  // namespace voxfuse
