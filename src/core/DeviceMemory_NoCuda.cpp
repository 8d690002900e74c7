// device_memory for builds without CUDA: every device request fails with a clear message.

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {

const char* deviceName(Device d) { return d == Device::CPU ? "cpu" : "cuda"; }

namespace device_memory {
namespace {
[[noreturn]] void noCuda() {
    throw DeviceError("this VoxFuse build has no CUDA support (rebuild with -DVOXFUSE_CUDA=ON)");
}
}  // namespace

bool builtWithCuda() { return false; }
bool cudaAvailable() { return false; }
std::string cudaDescription() { return "built without CUDA"; }
std::size_t freeDeviceBytes() { return 0; }
void* allocate(std::size_t) { noCuda(); }
void release(void*) noexcept {}
void* reserveGrowable(std::size_t) { return nullptr; }
void growGrowable(void*, std::size_t) { noCuda(); }
void releaseGrowable(void*) noexcept {}
std::size_t bytesInUse() { return 0; }
std::size_t peakBytesInUse() { return 0; }
void resetPeakBytes() {}
void copyHostToDevice(void*, const void*, std::size_t) { noCuda(); }
void copyDeviceToHost(void*, const void*, std::size_t) { noCuda(); }
void copyDeviceToDevice(void*, const void*, std::size_t) { noCuda(); }
void* allocatePinned(std::size_t) noexcept { return nullptr; }
void releasePinned(void*) noexcept {}
void fill(void*, int, std::size_t) { noCuda(); }
void fillPattern(void*, const void*, std::size_t, std::size_t) { noCuda(); }
void synchronize() {}
void* createEvent() { noCuda(); }
void destroyEvent(void*) noexcept {}
void recordEvent(void*) { noCuda(); }
float eventElapsedMs(void*, void*) { noCuda(); }
}  // namespace device_memory

}  // namespace voxfuse
