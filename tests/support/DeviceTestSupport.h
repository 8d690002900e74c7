#pragma once
// Running engine tests once per device: the CPU always, CUDA where a GPU is usable, and a visible skip
// otherwise. Instances on the GPU have "cuda" in their names (CTest labels them cuda too).
//
// Value-parametrised tests take a Device:  INSTANTIATE_TEST_SUITE_P(Devices, Suite, test::kAllDevices,
// test::DeviceName()); typed tests a device and a voxel type:   TYPED_TEST_SUITE(Suite, test::DevicesAndVoxels,
// test::DeviceAndVoxelName);

#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <string>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/Image.h"
#include "voxfuse/objects/RenderState.h"
#include "voxfuse/objects/Scene.h"
#include "voxfuse/objects/Voxel.h"
#include "voxfuse/objects/VoxelBlockHash.h"

namespace voxfuse::test {

// Skips the current test, saying why, when `device` cannot run here.
#define VF_SKIP_IF_UNAVAILABLE(device)                                                                           \
    do {                                                                                                         \
        if ((device) == ::voxfuse::Device::CUDA && !::voxfuse::device_memory::cudaAvailable())                   \
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
    ::testing::Types<DeviceAndVoxel<Device::CPU, VoxelS>, DeviceAndVoxel<Device::CPU, VoxelF>,
                     DeviceAndVoxel<Device::CPU, VoxelSRgb>, DeviceAndVoxel<Device::CPU, VoxelFRgb>,
                     DeviceAndVoxel<Device::CPU, VoxelSLabel>, DeviceAndVoxel<Device::CPU, VoxelSRgbLabel>,
                     DeviceAndVoxel<Device::CUDA, VoxelS>, DeviceAndVoxel<Device::CUDA, VoxelF>,
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

// ---- Bit-for-bit comparisons of what two devices computed, channel by channel ----
// Where both devices run the same arithmetic (integration, allocation, raycast at a given pose,
// meshing of a given map; both built without fused multiply-adds), every bit must agree: a tolerance
// there would pass over a race or a read of unwritten memory that changes a few voxels. The counts
// say which channel differs and how often, so that a failure on a lent GPU says what to look at.

// Whether two values have the same bytes (-0 and +0 differ; a NaN equals the same NaN).
template <class T>
bool sameBits(const T& a, const T& b) {
    return std::memcmp(&a, &b, sizeof(T)) == 0;
}

// Per channel, how many of `compared` elements differ.
struct ChannelDifferences {
    long long compared = 0;
    std::map<std::string, long long> differing;  // channel -> elements whose channel differs
    void count(const char* channel, bool differs) {
        if (differs) ++differing[channel];
    }
    bool none() const { return differing.empty(); }
    std::string describe() const {
        std::string s = std::to_string(compared) + " compared";
        for (const auto& [channel, n] : differing) s += ", " + channel + " differs in " + std::to_string(n);
        return s;
    }
};

// Every field of every voxel: sdf, depth weight, each colour channel and its weight, class and its weight.
template <class TVoxel>
ChannelDifferences voxelDifferences(const MemoryBlock<TVoxel>& a, const MemoryBlock<TVoxel>& b) {
    ChannelDifferences d;
    if (a.size() != b.size()) {
        d.count("array size", true);
        return d;
    }
    d.compared = (long long)a.size();
    for (std::size_t i = 0; i < a.size(); ++i) {
        const TVoxel &x = a.host()[i], &y = b.host()[i];
        d.count("sdf", !sameBits(x.sdf, y.sdf));
        d.count("w_depth", !sameBits(x.w_depth, y.w_depth));
        if constexpr (TVoxel::hasColor) {
            d.count("colour r", x.clr.x != y.clr.x);
            d.count("colour g", x.clr.y != y.clr.y);
            d.count("colour b", x.clr.z != y.clr.z);
            d.count("w_color", !sameBits(x.w_color, y.w_color));
        }
        if constexpr (TVoxel::hasLabel) {
            d.count("label", !sameBits(x.label, y.label));
            d.count("w_label", !sameBits(x.w_label, y.w_label));
        }
    }
    return d;
}

// Every channel of every pixel of two images of one element type (Vec4f, Vec2f, Vec4u8, float).
template <class T, int Channels>
void addImageDifferences(ChannelDifferences& d, const char* name, const T* a, const T* b, std::size_t pixels) {
    static_assert(Channels >= 1 && Channels <= 4, "one to four channels");
    for (std::size_t i = 0; i < pixels; ++i) {
        if constexpr (Channels == 1) {
            d.count(name, !sameBits(a[i], b[i]));
        } else {
            static const char* const kChannel[] = {"x", "y", "z", "w"};
            for (int c = 0; c < Channels; ++c)
                if (!sameBits((&a[i].x)[c], (&b[i].x)[c]))
                    d.count((std::string(name) + "." + kChannel[c]).c_str(), true);
        }
    }
    d.compared += (long long)pixels;
}
template <class T, int Channels>
void addImageDifferences(ChannelDifferences& d, const char* name, const Image<T>& a, const Image<T>& b) {
    if (a.size() != b.size()) {
        d.count((std::string(name) + " size").c_str(), true);
        return;
    }
    addImageDifferences<T, Channels>(d, name, a.host(), b.host(), a.pixelCount());
}

// A raycast's points, normals and depth ranges (host copies current).
inline ChannelDifferences raycastDifferences(const RenderState& a, const RenderState& b) {
    ChannelDifferences d;
    addImageDifferences<Vec4f, 4>(d, "point", a.points_world, b.points_world);
    addImageDifferences<Vec4f, 4>(d, "normal", a.normals_world, b.normals_world);
    addImageDifferences<Vec2f, 2>(d, "depth range", a.depth_range, b.depth_range);
    return d;
}

}  // namespace voxfuse::test
