#pragma once
// Semantic class ids as VoxFuse stores them: 16-bit, as read from a label image (one class id per
// pixel). kNoLabel marks pixels, voxels, vertices and points without a class.

#include <cstdint>

namespace voxfuse {

using ClassId = std::uint16_t;
constexpr ClassId kNoLabel = 0xFFFF;

}  // namespace voxfuse
