#pragma once
// Temporary memory of the device primitives (scans, selections, sorts), kept by an engine across
// frames so that a frame allocates nothing once the buffers have reached their working size.

#include <cstddef>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/MemoryBlock.h"

namespace voxfuse {

class DeviceScratch {
public:
    explicit DeviceScratch(Device where) : where_(where) {}

    Device device() const { return where_; }
    // At least `bytes` bytes on the scratch's device, 256-byte aligned; contents undefined. The pointer
    // stays valid until the next call.
    void* get(std::size_t bytes) {
        if (buffer_.size() < bytes) buffer_.allocate(bytes + bytes / 4, where_ == Device::CPU, where_ == Device::CUDA);
        return buffer_.data(where_);
    }
    // A few bytes of pinned host memory for results read back from the device (counts, flags).
    void* hostResult(std::size_t bytes) {
        if (host_result_.size() < bytes) host_result_.allocate(bytes, true, false, HostMemory::Pinned);
        return host_result_.host();
    }

private:
    Device where_;
    MemoryBlock<unsigned char> buffer_;
    MemoryBlock<unsigned char> host_result_;
};

}  // namespace voxfuse
