#pragma once
// Turning one raycast pixel into a display colour (or the intensity the rgbd tracker aligns to).

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/ClassLabel.h"
#include "voxfuse/shared/ColorTrackerTerms.h"  // intensityFromRgb
#include "voxfuse/shared/Raycast.h"

namespace voxfuse {

enum class RenderMode {
    Shaded,   // Lambertian, light at the camera
    Color,    // fused voxel colours (grey shading for voxel types without colour)
    Normals,  // world normal mapped to RGB
    Depth,    // distance along the optical axis, colour-mapped
    Class     // semantic class colours, shaded (grey shading for voxel types without labels)
};

constexpr Vec4u8 kBackground{0, 0, 0, 255};

VF_HOST_DEVICE inline Vec4u8 renderShaded(Vec3f normal, Vec3f to_camera_unit) {
    const unsigned char i = shadeIntensity(normal, to_camera_unit);
    return {i, i, i, 255};
}

VF_HOST_DEVICE inline Vec4u8 renderNormal(Vec3f n) {
    return {(unsigned char)(127.5f * (n.x + 1.f)), (unsigned char)(127.5f * (n.y + 1.f)),
            (unsigned char)(127.5f * (n.z + 1.f)), 255};
}

// A distinct, stable colour per class id; kNoLabel is grey. Ids 0-11 (where the common classes of
// small label sets lie) take twelve hues 30 degrees apart: 0-5 the six 60 degrees apart, saturated,
// 6-11 the six between them, paler and darker, so that hues 30 degrees apart never look alike.
// Larger ids step the hue by the golden ratio, with saturation alternating with the id's parity.
VF_HOST_DEVICE inline Vec3f classColor(ClassId id) {
    if (id == kNoLabel) return {150.f, 150.f, 150.f};
    constexpr unsigned char kFirstHues[12] = {0, 6, 2, 8, 4, 10, 1, 7, 3, 9, 5, 11};  // in 30-degree steps
    const float turns =
        id < 12 ? float(kFirstHues[id]) / 12.f : float(id) * 0.61803398875f - floorf(float(id) * 0.61803398875f);
    const float h = 6.f * turns;
    const bool pale = id < 12 ? id >= 6 : (id & 1) != 0;
    const float s = pale ? 0.5f : 0.85f, v = pale ? 0.85f : 0.95f;
    const int sector = int(h);
    const float f = h - float(sector), p = v * (1.f - s), q = v * (1.f - s * f), t = v * (1.f - s * (1.f - f));
    Vec3f rgb;
    switch (sector % 6) {
        case 0:
            rgb = {v, t, p};
            break;
        case 1:
            rgb = {q, v, p};
            break;
        case 2:
            rgb = {p, v, t};
            break;
        case 3:
            rgb = {p, q, v};
            break;
        case 4:
            rgb = {t, p, v};
            break;
        default:
            rgb = {v, p, q};
            break;
    }
    return rgb * 255.f;
}

// The class colour, shaded so that the shape stays readable.
VF_HOST_DEVICE inline Vec4u8 renderClass(ClassId id, Vec3f normal, Vec3f to_camera_unit) {
    return renderColor(classColor(id) * (float(shadeIntensity(normal, to_camera_unit)) / 255.f));
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

// The render of one raycast pixel (element i of the image) in `mode`; the voxels are read only for
// RenderMode::Color and RenderMode::Class.
template <class TVoxel, class TIndexData>
struct RenderRaycastPixel {
    const TVoxel* voxels;
    TIndexData index;
    RenderMode mode;
    float inv_voxel_size;
    float max_depth_m;   // of the depth colour map
    Vec3f camera_world;  // where the light is
    Mat4f T_camera_world;
    const Vec4f* points_world;
    const Vec4f* normals_world;
    Vec4u8* image;

    VF_HOST_DEVICE void operator()(int i) const {
        if (points_world[i].w <= 0.f) {
            image[i] = kBackground;
            return;
        }
        const Vec3f p = points_world[i].xyz(), n = normals_world[i].xyz();
        switch (mode) {
            case RenderMode::Shaded:
                image[i] = renderShaded(n, normalize(camera_world - p));
                break;
            case RenderMode::Normals:
                image[i] = renderNormal(n);
                break;
            case RenderMode::Depth:
                image[i] = renderDepth(transformPoint(T_camera_world, p).z, max_depth_m);
                break;
            case RenderMode::Color:
                if constexpr (TVoxel::hasColor)
                    image[i] = renderColor(readColorInterpolated(voxels, index, p * inv_voxel_size));
                else
                    image[i] = renderShaded(n, normalize(camera_world - p));
                break;
            case RenderMode::Class:
                if constexpr (TVoxel::hasLabel)
                    image[i] = renderClass(readLabelNearest(voxels, index, p * inv_voxel_size), n,
                                           normalize(camera_world - p));
                else
                    image[i] = renderShaded(n, normalize(camera_world - p));
                break;
        }
    }
};

// The map's colour at one raycast pixel as an intensity in [0, 1] (the luma intensityFromRgb gives a
// frame's pixels), -1 where nothing was hit or none of the voxels around the hit saw colour: the
// reference the rgbd tracker aligns a frame's intensities to (frame-to-model colour).
template <class TVoxel, class TIndexData>
struct RenderIntensityPixel {
    const TVoxel* voxels;
    TIndexData index;
    float inv_voxel_size;
    const Vec4f* points_world;
    float* intensity;

    VF_HOST_DEVICE void operator()(int i) const {
        intensity[i] =
            points_world[i].w > 0.f ? mapIntensityAt(voxels, index, points_world[i].xyz(), inv_voxel_size) : -1.f;
    }
};

}  // namespace voxfuse
