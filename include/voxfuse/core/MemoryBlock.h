#pragma once
// One owning buffer with an optional host copy and an optional device copy. Copies between them are
// explicit (no managed memory), so every transfer is visible at the call site.

#include <cstdlib>
#include <cstring>
#include <new>
#include <type_traits>
#include <utility>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {

template <typename T>
class MemoryBlock {
    static_assert(std::is_trivially_copyable<T>::value, "MemoryBlock holds trivially copyable elements only");

public:
    MemoryBlock() = default;
    MemoryBlock(std::size_t count, bool on_host, bool on_device) { allocate(count, on_host, on_device); }
    ~MemoryBlock() { release(); }

    MemoryBlock(const MemoryBlock&) = delete;
    MemoryBlock& operator=(const MemoryBlock&) = delete;
    MemoryBlock(MemoryBlock&& o) noexcept { swap(o); }
    MemoryBlock& operator=(MemoryBlock&& o) noexcept {
        if (this != &o) {
            release();
            swap(o);
        }
        return *this;
    }

    // Reallocates (contents are lost) unless the size and locations already match.
    void allocate(std::size_t count, bool on_host, bool on_device) {
        if (count == count_ && on_host == (host_ != nullptr || count == 0) &&
            on_device == (device_ != nullptr || count == 0))
            return;
        release();
        count_ = count;
        if (count == 0) return;
        if (on_host) {
            // 64-byte alignment keeps SIMD loads and cache lines happy in the CPU loops.
            const std::size_t bytes = ((count * sizeof(T) + 63) / 64) * 64;
            host_ = static_cast<T*>(std::aligned_alloc(64, bytes));
            if (!host_) throw std::bad_alloc();
        }
        if (on_device) device_ = static_cast<T*>(device_memory::allocate(count * sizeof(T)));
    }

    std::size_t size() const { return count_; }
    std::size_t bytes() const { return count_ * sizeof(T); }
    bool onHost() const { return host_ != nullptr; }
    bool onDevice() const { return device_ != nullptr; }

    T* host() { return host_; }
    const T* host() const { return host_; }
    T* device() { return device_; }
    const T* device() const { return device_; }
    T* data(Device where) { return where == Device::CPU ? host_ : device_; }
    const T* data(Device where) const { return where == Device::CPU ? host_ : device_; }

    // Adds a device copy if there is none (contents undefined until copied).
    void ensureOnDevice() {
        if (!device_ && count_) device_ = static_cast<T*>(device_memory::allocate(bytes()));
    }
    void copyHostToDevice() {
        requireBoth("copyHostToDevice");
        device_memory::copyHostToDevice(device_, host_, bytes());
    }
    void copyDeviceToHost() {
        requireBoth("copyDeviceToHost");
        device_memory::copyDeviceToHost(host_, device_, bytes());
    }
    // Sets every byte of every present copy.
    void fillBytes(int byte_value) {
        if (host_) std::memset(static_cast<void*>(host_), byte_value, bytes());
        if (device_) device_memory::fill(device_, byte_value, bytes());
    }
    // Host copy only: fills with a value (for types whose zero is not all-zero bytes).
    void fillHost(const T& value) {
        for (std::size_t i = 0; i < count_; ++i) host_[i] = value;
    }

private:
    void requireBoth(const char* what) const {
        if (!host_ || !device_) throw DeviceError(std::string("MemoryBlock::") + what + ": needs both a host and a device copy");
    }
    void release() noexcept {
        std::free(host_);
        if (device_) device_memory::release(device_);
        host_ = nullptr;
        device_ = nullptr;
        count_ = 0;
    }
    void swap(MemoryBlock& o) noexcept {
        std::swap(host_, o.host_);
        std::swap(device_, o.device_);
        std::swap(count_, o.count_);
    }

    T* host_ = nullptr;
    T* device_ = nullptr;
    std::size_t count_ = 0;
};

}  // namespace voxfuse
