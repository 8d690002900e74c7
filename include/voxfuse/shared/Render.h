#pragma once
// Turning one raycast pixel into a display colour.

#include "voxfuse/core/Math.h"
#include "voxfuse/shared/Raycast.h"

namespace voxfuse {

constexpr Vec4u8 kBackground{0, 0, 0, 255};

VF_HOST_DEVICE inline Vec4u8 renderShaded(Vec3f normal, Vec3f to_camera_unit) {
    const unsigned char i = shadeIntensity(normal, to_camera_unit);
    return {i, i, i, 255};
}

VF_HOST_DEVICE inline Vec4u8 renderNormal(Vec3f n) {
    return {(unsigned char)(127.5f * (n.x + 1.f)), (unsigned char)(127.5f * (n.y + 1.f)), (unsigned char)(127.5f * (n.z + 1.f)), 255};
}

VF_HOST_DEVICE inline Vec4u8 renderColor(Vec3f rgb) {
    return {(unsigned char)clampValue(rgb.x, 0.f, 255.f), (unsigned char)clampValue(rgb.y, 0.f, 255.f),
            (unsigned char)clampValue(rgb.z, 0.f, 255.f), 255};
}

// A perceptually ordered blue-to-yellow map (a cheap approximation of viridis) of depth / max_depth.
VF_HOST_DEVICE inline Vec4u8 renderDepth(float depth_m, float max_depth_m) {
    if (!(depth_m > 0.f)) return kBackground;
    const float t = clampValue(depth_m / max_depth_m, 0.f, 1.f);
    const float r = clampValue(-0.35f + 1.6f * t * t, 0.f, 1.f);
    const float g = clampValue(0.05f + 0.9f * t, 0.f, 1.f);
    const float b = clampValue(0.55f + 0.6f * t - 1.1f * t * t, 0.f, 1.f);
    return {(unsigned char)(255.f * r), (unsigned char)(255.f * g), (unsigned char)(255.f * b), 255};
}

}  // namespace voxfuse
