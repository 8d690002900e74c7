#pragma once
// A 2D image stored row-major in a MemoryBlock: pixel (x, y) is element x + y * width.

#include "voxfuse/core/Math.h"
#include "voxfuse/core/MemoryBlock.h"

namespace voxfuse {

template <typename T>
class Image {
public:
    Image() = default;
    Image(Vec2i size, bool on_host = true, bool on_device = false, HostMemory host_kind = HostMemory::Pageable) {
        resize(size, on_host, on_device, host_kind);
    }

    // Contents are lost unless the size and locations already match.
    void resize(Vec2i size, bool on_host = true, bool on_device = false, HostMemory host_kind = HostMemory::Pageable) {
        size_ = size;
        memory_.allocate(std::size_t(size.x) * std::size_t(size.y), on_host, on_device, host_kind);
    }
    Vec2i size() const { return size_; }
    int width() const { return size_.x; }
    int height() const { return size_.y; }
    std::size_t pixelCount() const { return memory_.size(); }
    bool empty() const { return memory_.size() == 0; }

    T* host() { return memory_.host(); }
    const T* host() const { return memory_.host(); }
    T* device() { return memory_.device(); }
    const T* device() const { return memory_.device(); }
    T& at(int x, int y) { return memory_.host()[x + y * size_.x]; }
    const T& at(int x, int y) const { return memory_.host()[x + y * size_.x]; }

    MemoryBlock<T>& memory() { return memory_; }
    const MemoryBlock<T>& memory() const { return memory_; }

private:
    Vec2i size_{0, 0};
    MemoryBlock<T> memory_;
};

}  // namespace voxfuse
