#pragma once
// The few CUDA runtime calls that host-side containers need, behind plain C++ declarations so that
// code using MemoryBlock never includes CUDA headers. A build without CUDA links stubs that throw
// DeviceError; a CUDA build on a machine without a GPU reports cudaAvailable() == false.

#include <cstddef>
#include <string>

namespace voxfuse {

// Where an engine runs and where its buffers live.
enum class Device { CPU, CUDA };

const char* deviceName(Device d);

namespace device_memory {
bool builtWithCuda();
// True when this build has CUDA and a usable GPU is present. Never throws.
bool cudaAvailable();
// A one-line description of the GPU (or why there is none), for logs and test skips.
std::string cudaDescription();
// Free memory of the current GPU now (cudaMemGetInfo), in bytes; 0 without a usable GPU. Never throws.
std::size_t freeDeviceBytes();
void* allocate(std::size_t bytes);
void release(void* ptr) noexcept;
// Memory that grows in place: reserveGrowable() reserves GPU addresses for `capacity_bytes` (no memory
// yet) and returns their start, or nullptr where the GPU or driver cannot (then allocate and copy);
// growGrowable() backs the first `bytes` of them with memory (throws DeviceError when it runs out),
// keeping what was there at the same addresses; releaseGrowable() frees the whole range. Counted in
// bytesInUse() as they are backed.
void* reserveGrowable(std::size_t capacity_bytes);
void growGrowable(void* base, std::size_t bytes);
void releaseGrowable(void* base) noexcept;
// GPU memory VoxFuse holds through allocate(), now and at most since the last resetPeakBytes() (for
// benchmarks: what a stage needs on the GPU).
std::size_t bytesInUse();
std::size_t peakBytesInUse();
void resetPeakBytes();
// Page-locked host memory: transfers from and to it run at full bus speed and without a hidden
// staging copy. Returns nullptr where there is no usable GPU (callers fall back to ordinary memory).
void* allocatePinned(std::size_t bytes) noexcept;
void releasePinned(void* ptr) noexcept;
void copyHostToDevice(void* dst_device, const void* src_host, std::size_t bytes);
void copyDeviceToHost(void* dst_host, const void* src_device, std::size_t bytes);
void copyDeviceToDevice(void* dst_device, const void* src_device, std::size_t bytes);
void fill(void* dst_device, int byte_value, std::size_t bytes);
// Writes `count` copies of the `pattern_bytes`-byte value at `pattern` (host memory, at most 64 bytes)
// to consecutive elements at dst_device.
void fillPattern(void* dst_device, const void* pattern, std::size_t pattern_bytes, std::size_t count);
// Waits for all work queued on the GPU; reports a fault of an earlier kernel as DeviceError.
void synchronize();
// CUDA events, for timing work on the GPU's own clock: record() queues a mark behind the work queued
// so far; elapsedMs() waits for `end` and returns the time between the two marks.
void* createEvent();
void destroyEvent(void* event) noexcept;
void recordEvent(void* event);
float eventElapsedMs(void* start, void* end);
}  // namespace device_memory

}  // namespace voxfuse
