#pragma once
// One owning buffer with an optional host copy and an optional device copy. Copies between them are
// explicit (no managed memory), so every transfer is visible at the call site.
//
// The block knows which copies are current. Asking for a copy to write to (the non-const host(),
// device() and data()) makes the other copy stale; the const accessors read and change nothing.
// updateHost() / updateDevice() copy only when the copy asked for is stale, so a buffer read on both
// sides crosses the bus once per change. Over-marking (a non-const accessor used only to read) costs a
// copy, never a wrong result.
//
// A host copy can live in page-locked ("pinned") memory, for buffers that cross the bus every frame
// (frame images, raycast results): those transfers then need no staging copy inside the driver.

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <new>
#include <string>
#include <type_traits>
#include <utility>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/Error.h"

#if defined(__unix__)
#include <sys/mman.h>
#endif

namespace voxfuse {

enum class HostMemory { Pageable, Pinned };

template <typename T>
class MemoryBlock {
    static_assert(std::is_trivially_copyable<T>::value, "MemoryBlock holds trivially copyable elements only");

public:
    MemoryBlock() = default;
    MemoryBlock(std::size_t count, bool on_host, bool on_device, HostMemory host_kind = HostMemory::Pageable) {
        allocate(count, on_host, on_device, host_kind);
    }
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

    // Reallocates (contents are lost) unless the size matches and the copies asked for exist (copies
    // not asked for are then kept too: a buffer reused every frame keeps both). The new copies count as
    // current: their contents are undefined until written. When an allocation fails the block is left
    // empty (size 0), never claiming a size it has no memory for: callers that grow buffers on demand
    // then allocate again on the next call instead of handing out a null pointer.
    void allocate(std::size_t count, bool on_host, bool on_device, HostMemory host_kind = HostMemory::Pageable) {
        // A pinned host copy serves where pageable memory was asked for, not the other way round.
        const bool host_ok =
            !on_host || (host_ && (host_kind == HostMemory::Pageable || host_kind_ == HostMemory::Pinned));
        if (count == count_ && (count == 0 || (host_ok && (!on_device || device_)))) return;
        release();
        count_ = count;
        host_kind_ = host_kind;
        host_current_ = device_current_ = true;
        if (count == 0) return;
        try {
            if (on_host) allocateHost();
            if (on_device) device_ = static_cast<T*>(device_memory::allocate(bytes()));
        } catch (...) {
            release();
            throw;
        }
    }

    std::size_t size() const { return count_; }
    std::size_t bytes() const { return count_ * sizeof(T); }
    bool onHost() const { return host_ != nullptr; }
    bool onDevice() const { return device_ != nullptr; }
    bool hostIsPinned() const { return host_ != nullptr && host_pinned_; }
    // True when the copy at `where` exists and holds the latest contents.
    bool isCurrent(Device where) const {
        return where == Device::CPU ? host_ != nullptr && host_current_ : device_ != nullptr && device_current_;
    }

    // Writable copies: the other copy becomes stale.
    T* host() {
        device_current_ = device_ == nullptr;
        host_current_ = true;
        return host_;
    }
    T* device() {
        host_current_ = host_ == nullptr;
        device_current_ = true;
        return device_;
    }
    T* data(Device where) { return where == Device::CPU ? host() : device(); }
    // Read-only copies: nothing changes.
    const T* host() const { return host_; }
    const T* device() const { return device_; }
    const T* data(Device where) const { return where == Device::CPU ? host_ : device_; }

    // Adds a copy if there is none (stale until copied or written).
    void ensureOnHost() {
        if (!host_ && count_) {
            allocateHost();
            host_current_ = false;
        }
    }
    void ensureOnDevice() {
        if (!device_ && count_) {
            device_ = static_cast<T*>(device_memory::allocate(bytes()));
            device_current_ = false;
        }
    }
    // Make the copy at `where` current (adding it if needed), copying only when it is stale.
    void updateHost() {
        ensureOnHost();
        if (!host_current_) copyDeviceToHost();
    }
    void updateDevice() {
        ensureOnDevice();
        if (!device_current_) copyHostToDevice();
    }
    void update(Device where) { where == Device::CPU ? updateHost() : updateDevice(); }

    // Whole-buffer copies; both copies are current afterwards.
    void copyHostToDevice() {
        requireBoth("copyHostToDevice");
        if (count_) device_memory::copyHostToDevice(device_, host_, bytes());
        host_current_ = device_current_ = true;
    }
    void copyDeviceToHost() {
        requireBoth("copyDeviceToHost");
        if (count_) device_memory::copyDeviceToHost(host_, device_, bytes());
        host_current_ = device_current_ = true;
    }

    // Element ranges between this block's `where` copy and memory outside it: `host_values` is host
    // memory. Writing a range makes the other copy stale.
    void writeRange(Device where, std::size_t offset, const T* host_values, std::size_t count) {
        requireRange(where, offset, count, "writeRange");
        if (!count) return;
        if (where == Device::CPU)
            std::memcpy(static_cast<void*>(host() + offset), host_values, count * sizeof(T));
        else
            device_memory::copyHostToDevice(device() + offset, host_values, count * sizeof(T));
    }
    void readRange(Device where, std::size_t offset, T* host_values, std::size_t count) const {
        requireRange(where, offset, count, "readRange");
        if (!count) return;
        if (where == Device::CPU)
            std::memcpy(static_cast<void*>(host_values), host_ + offset, count * sizeof(T));
        else
            device_memory::copyDeviceToHost(host_values, device_ + offset, count * sizeof(T));
    }
    // Copies `count` elements from `source` (its copy at `where`) into this block's copy at `where`.
    void copyRangeFrom(Device where, const MemoryBlock& source, std::size_t source_offset, std::size_t offset,
                       std::size_t count) {
        requireRange(where, offset, count, "copyRangeFrom");
        source.requireRange(where, source_offset, count, "copyRangeFrom (source)");
        if (!count) return;
        if (where == Device::CPU)
            std::memcpy(static_cast<void*>(host() + offset), source.host_ + source_offset, count * sizeof(T));
        else
            device_memory::copyDeviceToDevice(device() + offset, source.device_ + source_offset, count * sizeof(T));
    }

    // Sets `count` elements from `offset` of the copy at `where` to `value`; the other copy becomes stale.
    void fill(Device where, const T& value, std::size_t offset, std::size_t count) {
        requireRange(where, offset, count, "fill");
        if (!count) return;
        if (where == Device::CPU)
            std::fill(host() + offset, host() + offset + count, value);
        else
            device_memory::fillPattern(device() + offset, &value, sizeof(T), count);
    }
    // Sets every element of every present copy to `value`; both stay current.
    void fill(const T& value) {
        if (host_) std::fill(host_, host_ + count_, value);
        if (device_ && count_) device_memory::fillPattern(device_, &value, sizeof(T), count_);
        host_current_ = device_current_ = true;
    }
    // Sets every byte of every present copy; both stay current.
    void fillBytes(int byte_value) {
        if (host_) std::memset(static_cast<void*>(host_), byte_value, bytes());
        if (device_) device_memory::fill(device_, byte_value, bytes());
        host_current_ = device_current_ = true;
    }
    // Host copy only (kept for callers that never have a device copy).
    void fillHost(const T& value) { std::fill(host(), host() + count_, value); }

    // Grows a block that has only a host copy to `count` elements (at least its size), keeping its
    // contents; the elements added are undefined. The first growth from a plain allocation reserves
    // address space for `capacity` elements (on Unix an anonymous mapping without reservation, which
    // the OS backs with memory only where it is written, so an untouched reserve costs no memory); every
    // growth within it then keeps the data in place, with neither a copy nor a move. Without such a
    // mapping it reallocates and copies.
    void growHost(std::size_t count, std::size_t capacity) {
        if (device_) throw DeviceError("MemoryBlock::growHost: the block has a device copy");
        if (count < count_)
            throw Error("MemoryBlock::growHost: " + std::to_string(count) + " elements would shrink a block of " +
                        std::to_string(count_));
        if ((host_ && count <= host_capacity_) || (count == 0 && capacity == 0)) {
            count_ = count;
            return;
        }
        const std::size_t reserve = std::max(count, capacity);
        T* grown = nullptr;
        std::size_t grown_capacity = count, grown_mapped_bytes = 0;
#if defined(__unix__)
        void* mapped = mmap(nullptr, reserve * sizeof(T), PROT_READ | PROT_WRITE,
                            MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
        if (mapped != MAP_FAILED) {
            grown = static_cast<T*>(mapped);
            grown_capacity = reserve;
            grown_mapped_bytes = reserve * sizeof(T);
        }
#endif
        if (!grown) {
            grown = static_cast<T*>(std::aligned_alloc(64, ((count * sizeof(T) + 63) / 64) * 64));
            if (!grown) throw std::bad_alloc();
        }
        if (host_ && count_) std::memcpy(static_cast<void*>(grown), host_, bytes());
        freeHost();
        host_ = grown;
        host_capacity_ = grown_capacity;
        host_mapped_bytes_ = grown_mapped_bytes;
        host_kind_ = HostMemory::Pageable;
        host_current_ = device_current_ = true;
        count_ = count;
    }

    // The same for a block that has only a device copy, on the GPU's virtual memory management: the
    // first growth reserves GPU addresses for `capacity` elements and moves the contents there once;
    // every growth within them maps memory behind the data, with neither a copy nor a second array
    // (a copying growth holds the old and the new array at once, and stalls the frame). Returns false,
    // changing nothing, where the GPU or driver cannot reserve: the caller reallocates and copies.
    bool growDevice(std::size_t count, std::size_t capacity) {
        if (host_) throw DeviceError("MemoryBlock::growDevice: the block has a host copy");
        if (count < count_)
            throw Error("MemoryBlock::growDevice: " + std::to_string(count) + " elements would shrink a block of " +
                        std::to_string(count_));
        if (device_growable_ && count <= device_capacity_) {
            device_memory::growGrowable(device_, count * sizeof(T));
            count_ = count;
            return true;
        }
        const std::size_t reserve = std::max(count, capacity);
        void* base = device_memory::reserveGrowable(reserve * sizeof(T));
        if (!base) return false;
        try {
            device_memory::growGrowable(base, count * sizeof(T));
            if (device_ && count_) device_memory::copyDeviceToDevice(base, device_, bytes());
        } catch (...) {
            device_memory::releaseGrowable(base);
            throw;
        }
        freeDevice();
        device_ = static_cast<T*>(base);
        device_growable_ = true;
        device_capacity_ = reserve;
        device_current_ = true;
        count_ = count;
        return true;
    }

    // Drops one copy (the other must be current); a block that only the GPU uses keeps no host memory.
    void releaseHost() {
        if (!host_) return;
        if (!device_current_) throw DeviceError("MemoryBlock::releaseHost: the device copy is stale");
        freeHost();
    }
    void releaseDevice() {
        if (!device_) return;
        if (!host_current_) throw DeviceError("MemoryBlock::releaseDevice: the host copy is stale");
        freeDevice();
    }

private:
    void allocateHost() {
        host_pinned_ = false;
        host_capacity_ = count_;
        host_mapped_bytes_ = 0;
        if (host_kind_ == HostMemory::Pinned) {
            host_ = static_cast<T*>(device_memory::allocatePinned(bytes()));
            host_pinned_ = host_ != nullptr;
        }
        if (!host_) {
            // 64-byte alignment keeps SIMD loads and cache lines happy in the CPU loops.
            const std::size_t rounded = ((bytes() + 63) / 64) * 64;
            host_ = static_cast<T*>(std::aligned_alloc(64, rounded));
            if (!host_) throw std::bad_alloc();
        }
    }
    void freeHost() noexcept {
        if (host_mapped_bytes_)
            unmapHost();
        else if (host_pinned_)
            device_memory::releasePinned(host_);
        else
            std::free(host_);
        host_capacity_ = 0;
        host_mapped_bytes_ = 0;
        host_ = nullptr;
        host_pinned_ = false;
        host_current_ = true;
    }
    void freeDevice() noexcept {
        if (device_growable_)
            device_memory::releaseGrowable(device_);
        else if (device_)
            device_memory::release(device_);
        device_ = nullptr;
        device_growable_ = false;
        device_capacity_ = 0;
    }
    void unmapHost() noexcept {
#if defined(__unix__)
        munmap(static_cast<void*>(host_), host_mapped_bytes_);
#endif
    }
    void requireBoth(const char* what) const {
        if (count_ && (!host_ || !device_))
            throw DeviceError(std::string("MemoryBlock::") + what + ": needs both a host and a device copy");
    }
    void requireRange(Device where, std::size_t offset, std::size_t count, const char* what) const {
        if (count && !(where == Device::CPU ? host_ : device_))
            throw DeviceError(std::string("MemoryBlock::") + what + ": no " + deviceName(where) + " copy");
        if (offset > count_ || count > count_ - offset)
            throw Error(std::string("MemoryBlock::") + what + ": elements " + std::to_string(offset) + "+" +
                        std::to_string(count) + " outside a block of " + std::to_string(count_));
    }
    void release() noexcept {
        freeHost();
        freeDevice();
        count_ = 0;
        device_current_ = true;
    }
    void swap(MemoryBlock& o) noexcept {
        std::swap(host_, o.host_);
        std::swap(device_, o.device_);
        std::swap(count_, o.count_);
        std::swap(host_kind_, o.host_kind_);
        std::swap(host_pinned_, o.host_pinned_);
        std::swap(host_capacity_, o.host_capacity_);
        std::swap(host_mapped_bytes_, o.host_mapped_bytes_);
        std::swap(device_growable_, o.device_growable_);
        std::swap(device_capacity_, o.device_capacity_);
        std::swap(host_current_, o.host_current_);
        std::swap(device_current_, o.device_current_);
    }

    T* host_ = nullptr;
    T* device_ = nullptr;
    std::size_t count_ = 0;
    HostMemory host_kind_ = HostMemory::Pageable;
    bool host_pinned_ = false;           // host_ came from allocatePinned
    std::size_t host_capacity_ = 0;      // elements host_ can hold (more than count_ after growHost)
    std::size_t host_mapped_bytes_ = 0;  // host_ is a mapping of this many bytes (growHost), else 0
    bool device_growable_ = false;       // device_ came from reserveGrowable (growDevice)
    std::size_t device_capacity_ = 0;    // elements its reservation holds
    bool host_current_ = true;           // meaningful only while host_ exists
    bool device_current_ = true;         // meaningful only while device_ exists
};

// Copies all of `source`'s copy at `from` into `target`'s copy at `to` (equal sizes), across the bus
// where the two differ.
template <typename T>
void copyAcross(MemoryBlock<T>& target, Device to, const MemoryBlock<T>& source, Device from) {
    if (target.size() != source.size()) throw Error("copyAcross: the blocks differ in size");
    if (from == Device::CPU)
        target.writeRange(to, 0, source.host(), source.size());
    else if (to == Device::CPU)
        source.readRange(from, 0, target.host(), source.size());
    else
        target.copyRangeFrom(to, source, 0, 0, source.size());
}

// Keeps only the copy at `where`, bringing it up to date first.
template <typename T>
void keepOnly(MemoryBlock<T>& block, Device where) {
    if (where == Device::CPU) {
        block.updateHost();
        block.releaseDevice();
    } else {
        block.updateDevice();
        block.releaseHost();
    }
}

}  // namespace voxfuse
