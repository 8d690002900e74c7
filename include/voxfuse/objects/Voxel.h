#pragma once
// The voxel types. Each stores a truncated signed distance (normalised to [-1, 1] by the truncation
// band mu) and its weight; the *Rgb types add a colour and its weight, the *Label types a semantic
// class and its weight (shared/LabelFusion.h). The short types quantise the SDF to int16 (half the
// memory of float; step 1/32767 of mu).

#include <cmath>
#include <cstdint>

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/ClassLabel.h"

namespace voxfuse {

// The run-time names used on the command line and in settings files.
enum class VoxelType { S, F, SRgb, FRgb, SLabel, SRgbLabel };

// The stored value of a normalised SDF f in [-1, 1]: f * 32767 to the nearest integer (halves to
// even, as rintf). lrintf is one instruction on x86-64; rintf is a branch and four dependent ones
// without SSE4.1, where perf put a sixth of the CPU integration's samples.
VF_HOST_DEVICE inline std::int16_t quantiseSdf(float f) { return std::int16_t(lrintf(f * 32767.f)); }

struct VoxelS {
    static constexpr bool hasColor = false;
    static constexpr bool hasLabel = false;
    static constexpr const char* name = "s";
    std::int16_t sdf;
    std::uint8_t w_depth;

    VF_HOST_DEVICE static float sdfToFloat(std::int16_t v) { return float(v) * (1.f / 32767.f); }
    VF_HOST_DEVICE static std::int16_t sdfFromFloat(float f) { return quantiseSdf(f); }
    VF_HOST_DEVICE static VoxelS initial() { return {32767, 0}; }
};

struct VoxelF {
    static constexpr bool hasColor = false;
    static constexpr bool hasLabel = false;
    static constexpr const char* name = "f";
    float sdf;
    std::uint8_t w_depth;

    VF_HOST_DEVICE static float sdfToFloat(float v) { return v; }
    VF_HOST_DEVICE static float sdfFromFloat(float f) { return f; }
    VF_HOST_DEVICE static VoxelF initial() { return {1.f, 0}; }
};

struct VoxelSRgb {
    static constexpr bool hasColor = true;
    static constexpr bool hasLabel = false;
    static constexpr const char* name = "s_rgb";
    std::int16_t sdf;
    std::uint8_t w_depth;
    std::uint8_t w_color;
    Vec3u8 clr;

    VF_HOST_DEVICE static float sdfToFloat(std::int16_t v) { return float(v) * (1.f / 32767.f); }
    VF_HOST_DEVICE static std::int16_t sdfFromFloat(float f) { return quantiseSdf(f); }
    VF_HOST_DEVICE static VoxelSRgb initial() { return {32767, 0, 0, {0, 0, 0}}; }
};

struct VoxelFRgb {
    static constexpr bool hasColor = true;
    static constexpr bool hasLabel = false;
    static constexpr const char* name = "f_rgb";
    float sdf;
    std::uint8_t w_depth;
    std::uint8_t w_color;
    Vec3u8 clr;

    VF_HOST_DEVICE static float sdfToFloat(float v) { return v; }
    VF_HOST_DEVICE static float sdfFromFloat(float f) { return f; }
    VF_HOST_DEVICE static VoxelFRgb initial() { return {1.f, 0, 0, {0, 0, 0}}; }
};

// The semantic types: short SDF, without and with colour (6 and 10 bytes). `label` is meaningful
// only where w_label > 0.
struct VoxelSLabel {
    static constexpr bool hasColor = false;
    static constexpr bool hasLabel = true;
    static constexpr const char* name = "s_label";
    std::int16_t sdf;
    ClassId label;
    std::uint8_t w_depth;
    std::uint8_t w_label;

    VF_HOST_DEVICE static float sdfToFloat(std::int16_t v) { return float(v) * (1.f / 32767.f); }
    VF_HOST_DEVICE static std::int16_t sdfFromFloat(float f) { return quantiseSdf(f); }
    VF_HOST_DEVICE static VoxelSLabel initial() { return {32767, kNoLabel, 0, 0}; }
};

struct VoxelSRgbLabel {
    static constexpr bool hasColor = true;
    static constexpr bool hasLabel = true;
    static constexpr const char* name = "s_rgb_label";
    std::int16_t sdf;
    ClassId label;
    std::uint8_t w_depth;
    std::uint8_t w_color;
    std::uint8_t w_label;
    Vec3u8 clr;

    VF_HOST_DEVICE static float sdfToFloat(std::int16_t v) { return float(v) * (1.f / 32767.f); }
    VF_HOST_DEVICE static std::int16_t sdfFromFloat(float f) { return quantiseSdf(f); }
    VF_HOST_DEVICE static VoxelSRgbLabel initial() { return {32767, kNoLabel, 0, 0, 0, {0, 0, 0}}; }
};

static_assert(sizeof(VoxelSLabel) == 6 && sizeof(VoxelSRgbLabel) == 10, "semantic voxels stay packed");

}  // namespace voxfuse
