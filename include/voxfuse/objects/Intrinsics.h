#pragma once
// Pinhole camera intrinsics in pixels (Matlab/OpenCV convention: pixel centres at integers).

#include "voxfuse/core/Math.h"

namespace voxfuse {

struct Intrinsics {
    int width = 0, height = 0;  // pixels
    float fx = 0.f, fy = 0.f;   // focal lengths, pixels
    float cx = 0.f, cy = 0.f;   // principal point, pixels

    VF_HOST_DEVICE Vec2i size() const { return {width, height}; }
    // Camera-frame point (metres, z forward) to pixel coordinates.
    VF_HOST_DEVICE Vec2f project(Vec3f p_camera) const {
        return {fx * p_camera.x / p_camera.z + cx, fy * p_camera.y / p_camera.z + cy};
    }
    // Index (x + y * width) of the pixel nearest to pixel coordinates `px`, or -1 outside the image
    // (NaN included). Branch-free (& rather than &&, selects rather than an early return), so that
    // loops over voxels or pixels that look pixels up vectorise; the casts see in-range values only.
    VF_HOST_DEVICE int nearestPixelIndex(Vec2f px) const { return nearestPixelIndexIn(px, width, height); }
    // The same for an image of width x height pixels.
    VF_HOST_DEVICE static int nearestPixelIndexIn(Vec2f px, int width, int height) {
        const bool inside =
            (px.x >= -0.5f) & (px.y >= -0.5f) & (px.x < float(width) - 0.5f) & (px.y < float(height) - 0.5f);
        const int u = int((inside ? px.x : 0.f) + 0.5f), v = int((inside ? px.y : 0.f) + 0.5f);
        return inside & (u < width) & (v < height) ? u + v * width : -1;
    }
    // Pixel (u, v) at depth z (metres along the optical axis) to a camera-frame point.
    VF_HOST_DEVICE Vec3f unproject(float u, float v, float depth_m) const {
        return {(u - cx) * depth_m / fx, (v - cy) * depth_m / fy, depth_m};
    }
    // The intrinsics of an image downsampled by `factor` (2 for one pyramid level), keeping pixel centres consistent.
    Intrinsics downsampled(int factor) const {
        Intrinsics r = *this;
        r.width = width / factor;
        r.height = height / factor;
        r.fx = fx / factor;
        r.fy = fy / factor;
        r.cx = (cx + 0.5f) / factor - 0.5f;
        r.cy = (cy + 0.5f) / factor - 0.5f;
        return r;
    }
    // The same camera seen through an image of another resolution (same field of view).
    Intrinsics resized(int new_width, int new_height) const {
        Intrinsics r = *this;
        const float sx = float(new_width) / float(width), sy = float(new_height) / float(height);
        r.width = new_width;
        r.height = new_height;
        r.fx = fx * sx;
        r.fy = fy * sy;
        r.cx = (cx + 0.5f) * sx - 0.5f;
        r.cy = (cy + 0.5f) * sy - 0.5f;
        return r;
    }
    bool valid() const { return width > 0 && height > 0 && fx > 0.f && fy > 0.f; }
};

}  // namespace voxfuse
