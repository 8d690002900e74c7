#pragma once
// The dense index: one voxel per grid cell of a fixed box, stored x-fastest. Simple and fast for a
// bounded workspace; memory is size.x * size.y * size.z voxels whatever the scene holds.

#include <cstddef>

#include "voxfuse/core/Math.h"

namespace voxfuse {

enum class IndexType { Dense, Hash };

class PlainVoxelArray {
public:
    static constexpr const char* name = "dense";

    // What device-agnostic code needs to address a voxel (trivially copyable).
    struct Data {
        Vec3i offset;  // grid coordinate of the first voxel (voxel units)
        Vec3i size;    // number of voxels along x, y, z
    };

    explicit PlainVoxelArray(Vec3i offset = {-256, -256, 0}, Vec3i size = {512, 512, 512}) : data_{offset, size} {}

    const Data& data() const { return data_; }
    std::size_t voxelCount() const { return std::size_t(data_.size.x) * data_.size.y * data_.size.z; }

private:
    Data data_;
};

}  // namespace voxfuse
