#pragma once
// Running engine tests once per device: the CPU always, CUDA where a GPU is usable, and a visible skip
// otherwise. Instances on the GPU have "cuda" in their names (CTest labels them cuda too).
//
// Value-parametrised tests take a Device:  INSTANTIATE_TEST_SUITE_P(Devices, Suite, test::kAllDevices, test::DeviceName());
// typed tests a device and a voxel type:   TYPED_TEST_SUITE(Suite, test::DevicesAndVoxels, test::DeviceAndVoxelName);

#include <gtest/gtest.h>

#include <string>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/objects/Scene.h"
#include "voxfuse/objects/Voxel.h"
#include "voxfuse/objects/VoxelBlockHash.h"

namespace voxfuse::test {

// Skips the current test, saying why, when `device` cannot run here.
#define VF_SKIP_IF_UNAVAILABLE(device)                                                                     \
    do {                                                                                                   \
        if ((device) == ::voxfuse::Device::CUDA && !::voxfuse::device_memory::cudaAvailable())             \
            GTEST_SKIP() << "no usable GPU for the CUDA layer: " << ::voxfuse::device_memory::cudaDescription(); \
    } while (0)

inline const auto kAllDevices = ::testing::Values(Device::CPU, Device::CUDA);

struct DeviceName {
    std::string operator()(const ::testing::TestParamInfo<Device>& info) const { return deviceName(info.param); }
};

template <Device D, class TVoxel>
struct DeviceAndVoxel {
    static constexpr Device device = D;
    using Voxel = TVoxel;
};

using DevicesAndVoxels =
    ::testing::Types<DeviceAndVoxel<Device::CPU, VoxelS>, DeviceAndVoxel<Device::CPU, VoxelF>, DeviceAndVoxel<Device::CPU, VoxelSRgb>,
                     DeviceAndVoxel<Device::CPU, VoxelFRgb>, DeviceAndVoxel<Device::CPU, VoxelSLabel>,
                     DeviceAndVoxel<Device::CPU, VoxelSRgbLabel>, DeviceAndVoxel<Device::CUDA, VoxelS>, DeviceAndVoxel<Device::CUDA, VoxelF>,
                     DeviceAndVoxel<Device::CUDA, VoxelSRgb>, DeviceAndVoxel<Device::CUDA, VoxelFRgb>,
                     DeviceAndVoxel<Device::CUDA, VoxelSLabel>, DeviceAndVoxel<Device::CUDA, VoxelSRgbLabel>>;

struct DeviceAndVoxelName {
    template <class T>
    static std::string GetName(int) {
        return std::string(deviceName(T::device)) + "_" + T::Voxel::name;
    }
};

// A host copy of a scene for inspection (the scene itself when it is on the host already).
template <class TVoxel, class TIndex>
Scene<TVoxel, TIndex> onHost(const Scene<TVoxel, TIndex>& scene) {
    return scene.copyTo(Device::CPU);
}

// Field by field (structs have padding bytes, which memcmp would compare too).
inline bool sameEntry(const HashEntry& a, const HashEntry& b) {
    return a.pos.x == b.pos.x && a.pos.y == b.pos.y && a.pos.z == b.pos.z && a.next == b.next && a.ptr == b.ptr;
}
template <class TVoxel>
bool sameVoxel(const TVoxel& a, const TVoxel& b) {
    bool same = a.sdf == b.sdf && a.w_depth == b.w_depth;
    if constexpr (TVoxel::hasColor) same = same && a.w_color == b.w_color && a.clr == b.clr;
    if constexpr (TVoxel::hasLabel) same = same && a.w_label == b.w_label && a.label == b.label;
    return same;
}

// The index of the first entry where two tables in host memory differ, or -1 when they are the same.
inline int firstDifferentEntry(const VoxelBlockHash& a, const VoxelBlockHash& b) {
    if (a.entryCount() != b.entryCount()) return 0;
    for (int i = 0; i < a.entryCount(); ++i)
        if (!sameEntry(a.data().entries[i], b.data().entries[i])) return i;
    return -1;
}
// The index of the first voxel where two host voxel arrays differ, or -1.
template <class TVoxel>
long long firstDifferentVoxel(const MemoryBlock<TVoxel>& a, const MemoryBlock<TVoxel>& b) {
    if (a.size() != b.size()) return 0;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (!sameVoxel(a.host()[i], b.host()[i])) return (long long)i;
    return -1;
}

}  // namespace voxfuse::test
