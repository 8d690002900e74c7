// device_memory on the CUDA runtime. A CUDA build still runs on machines without a GPU: every entry
// point but cudaAvailable() then throws DeviceError.

#include <cuda.h>  // the driver API's types only: its functions come through the runtime (below)

#include <cstring>
#include <mutex>
#include <unordered_map>
#include <utility>
#include <vector>

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
    void add(std::size_t bytes) {
        in_use += bytes;
        if (in_use > peak) peak = in_use;
    }
};
AllocationLedger& ledger() {
    static AllocationLedger l;
    return l;
}

// ---- Growable allocations: CUDA's virtual memory management ----
// The driver API's functions are looked up through the runtime (cudaGetDriverEntryPointByVersion), not
// linked: a library linked to libcuda would not even load on a machine without the NVIDIA driver,
// where the CPU layer must still run.
struct VirtualMemoryCalls {
    decltype(&cuDeviceGet) deviceGet = nullptr;
    decltype(&cuDeviceGetAttribute) deviceGetAttribute = nullptr;
    decltype(&cuMemGetAllocationGranularity) granularity = nullptr;
    decltype(&cuMemAddressReserve) addressReserve = nullptr;
    decltype(&cuMemAddressFree) addressFree = nullptr;
    decltype(&cuMemCreate) create = nullptr;
    decltype(&cuMemRelease) release = nullptr;
    decltype(&cuMemMap) map = nullptr;
    decltype(&cuMemUnmap) unmap = nullptr;
    decltype(&cuMemSetAccess) setAccess = nullptr;
    bool usable = false;  // every call found, and the current GPU supports them
    int device = 0;
    CUmemAllocationProp prop{};
    std::size_t granularity_bytes = 0;
};

template <class F>
bool lookUp(const char* symbol, F& fn) {
    void* p = nullptr;
    cudaDriverEntryPointQueryResult found{};
    if (!cuda::succeeded(cudaGetDriverEntryPointByVersion(symbol, &p, 12000, cudaEnableDefault, &found)) ||
        found != cudaDriverEntryPointSuccess)
        return false;
    fn = reinterpret_cast<F>(p);
    return p != nullptr;
}

// A reserved range of GPU addresses, backed from its start by the chunks mapped so far.
struct GrowableRegion {
    std::size_t reserved_bytes = 0;
    std::size_t mapped_bytes = 0;
    std::vector<std::pair<CUmemGenericAllocationHandle, std::size_t>> chunks;
};
std::size_t roundUp(std::size_t bytes, std::size_t granularity) {
    return (bytes + granularity - 1) / granularity * granularity;
}
// The regions by base address, under the ledger's lock.
std::unordered_map<void*, GrowableRegion>& growableRegions() {
    static std::unordered_map<void*, GrowableRegion> regions;
    return regions;
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
                   std::to_string(CUDART_VERSION / 1000) + "." + std::to_string(CUDART_VERSION % 1000 / 10) +
                   " runtime)";
        return std::string("no usable CUDA device (") + cudaGetErrorString(status) + ")";
    }
    if (count == 0) return "no CUDA device";
    cudaDeviceProp prop{};
    int device = 0;
    if (!cuda::succeeded(cudaGetDevice(&device)) || !cuda::succeeded(cudaGetDeviceProperties(&prop, device)))
        return "CUDA device (unknown)";
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
    l.add(bytes);
    return p;
}

namespace {
const VirtualMemoryCalls& virtualMemory() {
    static const VirtualMemoryCalls calls = [] {
        VirtualMemoryCalls c;
        if (!cudaAvailable()) return c;
        const bool found = lookUp("cuDeviceGet", c.deviceGet) && lookUp("cuDeviceGetAttribute", c.deviceGetAttribute) &&
                           lookUp("cuMemGetAllocationGranularity", c.granularity) &&
                           lookUp("cuMemAddressReserve", c.addressReserve) &&
                           lookUp("cuMemAddressFree", c.addressFree) && lookUp("cuMemCreate", c.create) &&
                           lookUp("cuMemRelease", c.release) && lookUp("cuMemMap", c.map) &&
                           lookUp("cuMemUnmap", c.unmap) && lookUp("cuMemSetAccess", c.setAccess);
        CUdevice device = 0;
        int supported = 0;
        if (!found || !cuda::succeeded(cudaGetDevice(&c.device)) || c.deviceGet(&device, c.device) != CUDA_SUCCESS ||
            c.deviceGetAttribute(&supported, CU_DEVICE_ATTRIBUTE_VIRTUAL_MEMORY_MANAGEMENT_SUPPORTED, device) !=
                CUDA_SUCCESS ||
            !supported)
            return c;
        c.prop.type = CU_MEM_ALLOCATION_TYPE_PINNED;
        c.prop.location.type = CU_MEM_LOCATION_TYPE_DEVICE;
        c.prop.location.id = c.device;
        c.usable = c.granularity(&c.granularity_bytes, &c.prop, CU_MEM_ALLOC_GRANULARITY_RECOMMENDED) == CUDA_SUCCESS &&
                   c.granularity_bytes > 0;
        return c;
    }();
    return calls;
}
}  // namespace

void* reserveGrowable(std::size_t capacity_bytes) {
    const VirtualMemoryCalls& vm = virtualMemory();
    if (!vm.usable || capacity_bytes == 0) return nullptr;
    const std::size_t reserved = roundUp(capacity_bytes, vm.granularity_bytes);
    CUdeviceptr base = 0;
    if (vm.addressReserve(&base, reserved, 0, 0, 0) != CUDA_SUCCESS) return nullptr;  // the caller copies instead
    void* p = reinterpret_cast<void*>(base);
    AllocationLedger& l = ledger();
    const std::lock_guard<std::mutex> lock(l.mutex);
    try {
        growableRegions()[p].reserved_bytes = reserved;
    } catch (...) {
        vm.addressFree(base, reserved);
        throw;
    }
    return p;
}

void growGrowable(void* base, std::size_t bytes) {
    const VirtualMemoryCalls& vm = virtualMemory();
    AllocationLedger& l = ledger();
    const std::lock_guard<std::mutex> lock(l.mutex);
    const auto it = growableRegions().find(base);
    if (it == growableRegions().end()) throw DeviceError("growGrowable: not a growable allocation");
    GrowableRegion& region = it->second;
    if (bytes <= region.mapped_bytes) return;
    const std::size_t target = roundUp(bytes, vm.granularity_bytes);
    if (target > region.reserved_bytes)
        throw DeviceError("growGrowable: " + std::to_string(bytes) + " bytes exceed the " +
                          std::to_string(region.reserved_bytes) + " reserved");
    const std::size_t chunk = target - region.mapped_bytes;
    const CUdeviceptr at = reinterpret_cast<CUdeviceptr>(base) + region.mapped_bytes;
    CUmemGenericAllocationHandle handle{};
    CUresult status = vm.create(&handle, chunk, &vm.prop, 0);
    if (status != CUDA_SUCCESS)
        throw DeviceError("cuMemCreate of " + std::to_string(chunk >> 20) +
                          " MiB failed (GPU memory exhausted?), CUresult " + std::to_string(int(status)));
    status = vm.map(at, chunk, 0, handle, 0);
    if (status == CUDA_SUCCESS) {
        CUmemAccessDesc access{};
        access.location = vm.prop.location;
        access.flags = CU_MEM_ACCESS_FLAGS_PROT_READWRITE;
        status = vm.setAccess(at, chunk, &access, 1);
        if (status != CUDA_SUCCESS) vm.unmap(at, chunk);
    }
    if (status != CUDA_SUCCESS) {
        vm.release(handle);
        throw DeviceError("mapping " + std::to_string(chunk >> 20) + " MiB of GPU memory failed, CUresult " +
                          std::to_string(int(status)));
    }
    region.chunks.emplace_back(handle, chunk);
    region.mapped_bytes = target;
    l.add(chunk);
}

void releaseGrowable(void* base) noexcept {
    if (!base) return;
    const VirtualMemoryCalls& vm = virtualMemory();
    AllocationLedger& l = ledger();
    const std::lock_guard<std::mutex> lock(l.mutex);
    const auto it = growableRegions().find(base);
    if (it == growableRegions().end()) return;
    const GrowableRegion& region = it->second;
    // Nothing may still run on the memory: unmapping it under a running kernel faults the kernel.
    cuda::succeeded(cudaDeviceSynchronize());
    if (region.mapped_bytes) vm.unmap(reinterpret_cast<CUdeviceptr>(base), region.mapped_bytes);
    for (const auto& chunk : region.chunks) vm.release(chunk.first);
    vm.addressFree(reinterpret_cast<CUdeviceptr>(base), region.reserved_bytes);
    l.in_use -= region.mapped_bytes;
    growableRegions().erase(it);
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

void copyHostToDevice(void* dst, const void* src, std::size_t bytes) {
    VF_CUDA_CHECK(cudaMemcpy(dst, src, bytes, cudaMemcpyHostToDevice));
}
void copyDeviceToHost(void* dst, const void* src, std::size_t bytes) {
    VF_CUDA_CHECK(cudaMemcpy(dst, src, bytes, cudaMemcpyDeviceToHost));
}
void copyDeviceToDevice(void* dst, const void* src, std::size_t bytes) {
    VF_CUDA_CHECK(cudaMemcpy(dst, src, bytes, cudaMemcpyDeviceToDevice));
}
void fill(void* dst, int byte_value, std::size_t bytes) { VF_CUDA_CHECK(cudaMemset(dst, byte_value, bytes)); }

void fillPattern(void* dst, const void* pattern, std::size_t pattern_bytes, std::size_t count) {
    if (pattern_bytes == 0 || pattern_bytes > sizeof(FillPattern))
        throw DeviceError("fillPattern: element size must be 1..64 bytes");
    if (count == 0) return;
    FillPattern p{};
    std::memcpy(p.bytes, pattern, pattern_bytes);
    const unsigned threads = 256;
    const std::size_t blocks = (count + threads - 1) / threads;
    fillPatternKernel<<<unsigned(blocks), threads>>>(static_cast<unsigned char*>(dst), p, unsigned(pattern_bytes),
                                                     count);
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
