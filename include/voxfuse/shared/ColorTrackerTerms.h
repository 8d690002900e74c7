#pragma once
// Photometric tracking terms (the colour tracker of section 4.1 of the InfiniTAM report): model
// surface points carrying an intensity are projected into the current colour image, and the residual
// is the difference of intensities. Also the per-pixel image operations it needs: intensity from RGB,
// the intensity pyramid and Sobel gradients.

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/Intrinsics.h"
#include "voxfuse/shared/DepthTrackerTerms.h"

namespace voxfuse {

// A model surface point (world coordinates) and its intensity in [0, 1]; intensity < 0 marks a point
// without colour (no surface, or outside the image it was coloured from).
struct ColorPoint {
    Vec3f p_world;
    float intensity;
};

// What every point of one photometric iteration shares.
struct ColorTermParams {
    Mat4f T_camera_world;  // inverse of the pose estimate (world to the current depth camera)
    Mat4f T_rgb_depth;     // depth-camera to colour-camera coordinates (inverse of the calibration's T_depth_rgb)
    Intrinsics rgb;        // the colour camera at this pyramid level
};

// Luma (ITU-R BT.601) in [0, 1].
VF_HOST_DEVICE inline float intensityFromRgb(Vec4u8 c) {
    return (0.299f * float(c.x) + 0.587f * float(c.y) + 0.114f * float(c.z)) * (1.f / 255.f);
}

// One pixel of the next pyramid level: the mean of its 2x2 block.
VF_HOST_DEVICE inline float downsampleIntensityPixel(const float* in, Vec2i in_size, int x, int y) {
    const int x0 = 2 * x, y0 = 2 * y;
    const int x1 = x0 + 1 < in_size.x ? x0 + 1 : x0, y1 = y0 + 1 < in_size.y ? y0 + 1 : y0;
    return 0.25f *
           (in[x0 + y0 * in_size.x] + in[x1 + y0 * in_size.x] + in[x0 + y1 * in_size.x] + in[x1 + y1 * in_size.x]);
}

// Sobel gradient (intensity per pixel); zero on the one-pixel border.
VF_HOST_DEVICE inline Vec2f sobelGradientPixel(const float* in, Vec2i size, int x, int y) {
    if (x < 1 || y < 1 || x >= size.x - 1 || y >= size.y - 1) return {0.f, 0.f};
    const float* r0 = in + (y - 1) * size.x + x;
    const float* r1 = r0 + size.x;
    const float* r2 = r1 + size.x;
    const float gx = (r0[1] - r0[-1]) + 2.f * (r1[1] - r1[-1]) + (r2[1] - r2[-1]);
    const float gy = (r2[-1] + 2.f * r2[0] + r2[1]) - (r0[-1] + 2.f * r0[0] + r0[1]);
    return {gx * 0.125f, gy * 0.125f};
}

// Bilinear interpolation at (x, y), pixel centres at integers; the caller keeps x in [0, width - 1)
// and y in [0, height - 1).
template <typename T>
VF_HOST_DEVICE inline T sampleBilinear(const T* image, int width, float x, float y) {
    const int x0 = int(x), y0 = int(y);
    const float fx = x - float(x0), fy = y - float(y0);
    const T* p = image + x0 + y0 * width;
    return (p[0] * (1.f - fx) + p[1] * fx) * (1.f - fy) + (p[width] * (1.f - fx) + p[width + 1] * fx) * fy;
}

// True when (x, y) lies at least one pixel inside an image of `size` (room for bilinear samples of
// Sobel gradients, which are zero on the border).
VF_HOST_DEVICE inline bool insideForSampling(Vec2f px, Vec2i size) {
    return px.x >= 1.f && px.y >= 1.f && px.x < float(size.x - 2) && px.y < float(size.y - 2);
}

// Colours a model point with the image of an earlier frame, seen by a colour camera at T_rgb_world.
VF_HOST_DEVICE inline ColorPoint colorPointFromModel(Vec4f p_world, const float* intensity, Vec2i size,
                                                     const Mat4f& T_rgb_world, const Intrinsics& rgb) {
    ColorPoint c{p_world.xyz(), -1.f};
    if (p_world.w <= 0.f) return c;
    const Vec3f p = transformPoint(T_rgb_world, c.p_world);
    if (p.z <= 1e-6f) return c;
    const Vec2f px = rgb.project(p);
    if (!insideForSampling(px, size)) return c;
    c.intensity = sampleBilinear(intensity, size.x, px.x, px.y);
    return c;
}

// The photometric term of one model point: r = I(pi(T_rgb_depth * T^-1 * p)) - intensity, and its
// Jacobian for the update T * exp(x), x = (omega, v) in depth-camera coordinates. With a = R_rgb_depth^T *
// dI/dp_rgb, a moved point p_d' = p_d - omega x p_d - v gives J = [a x p_d, -a].
VF_HOST_DEVICE inline bool photometricTerm(const ColorPoint& point, const float* intensity, const Vec2f* gradient,
                                           Vec2i size, const ColorTermParams& p, float J[6], float& residual) {
    if (point.intensity < 0.f) return false;
    const Vec3f p_d = transformPoint(p.T_camera_world, point.p_world);
    const Vec3f p_c = transformPoint(p.T_rgb_depth, p_d);
    if (p_c.z <= 1e-6f) return false;
    const Vec2f px = p.rgb.project(p_c);
    if (!insideForSampling(px, size)) return false;
    residual = sampleBilinear(intensity, size.x, px.x, px.y) - point.intensity;
    const Vec2f g = sampleBilinear(gradient, size.x, px.x, px.y);
    const float inv_z = 1.f / p_c.z;
    const Vec3f g_c{g.x * p.rgb.fx * inv_z, g.y * p.rgb.fy * inv_z,
                    -(g.x * p.rgb.fx * p_c.x + g.y * p.rgb.fy * p_c.y) * inv_z * inv_z};
    const Vec3f a = rotateInverse(p.T_rgb_depth, g_c);
    const Vec3f axp = cross(a, p_d);
    J[0] = axp.x;
    J[1] = axp.y;
    J[2] = axp.z;
    J[3] = -a.x;
    J[4] = -a.y;
    J[5] = -a.z;
    return true;
}

// A far-field point: the depth `depth_m` at pixel (x, y) of a keyframe's depth camera (a depth beyond
// the map's range, which the map does not hold) placed in the world and coloured by the keyframe's
// colour image (`intensity`, `gradient` of `size`, taken by `rgb` at T_rgb_world). Its squared
// intensity gradient there goes to `gradient_sq` (the keyframe keeps its best textured points); -1
// for a point without colour.
VF_HOST_DEVICE inline ColorPoint farFieldPoint(float depth_m, int x, int y, const Intrinsics& depth_camera,
                                               const Mat4f& T_world_camera, const float* intensity,
                                               const Vec2f* gradient, Vec2i size, const Mat4f& T_rgb_world,
                                               const Intrinsics& rgb, float& gradient_sq) {
    gradient_sq = -1.f;
    ColorPoint c{Vec3f{0.f, 0.f, 0.f}, -1.f};
    if (!(depth_m > 0.f)) return c;
    const Vec3f p_world = transformPoint(T_world_camera, depth_camera.unproject(float(x), float(y), depth_m));
    c = colorPointFromModel(Vec4f{p_world.x, p_world.y, p_world.z, 1.f}, intensity, size, T_rgb_world, rgb);
    if (c.intensity < 0.f) return c;
    const Vec2f px = rgb.project(transformPoint(T_rgb_world, p_world));
    const Vec2f g = sampleBilinear(gradient, size.x, px.x, px.y);
    gradient_sq = g.x * g.x + g.y * g.y;
    return c;
}

// A far-field point as the current frame sees it: without colour (-1) where it falls outside the
// depth image or where the frame measured depth within the map's range at its pixel, a surface in
// front of it (`depth` holds only those).
VF_HOST_DEVICE inline ColorPoint unhiddenFarFieldPoint(const ColorPoint& point, const float* depth, Vec2i size,
                                                       const Mat4f& T_camera_world, const Intrinsics& depth_camera) {
    ColorPoint c = point;
    if (c.intensity < 0.f) return c;
    const Vec3f p = transformPoint(T_camera_world, c.p_world);
    bool seen = p.z > 0.f;
    if (seen) {
        // Bounds are tested on the float pixel coordinates, before any conversion: a point just in
        // front of the camera projects far outside any int's range (a conversion that is undefined
        // behaviour, and that x86 and CUDA answer differently).
        const int i = Intrinsics::nearestPixelIndexIn(depth_camera.project(p), size.x, size.y);
        seen = i >= 0 && !(depth[i] > 0.f);
    }
    if (!seen) c.intensity = -1.f;
    return c;
}

// ---- Loop bodies of the device layers ----

struct IntensityPixels {
    const Vec4u8* rgb;
    float* intensity;
    VF_HOST_DEVICE void operator()(int i) const { intensity[i] = intensityFromRgb(rgb[i]); }
};

struct DownsampleIntensityPixels {
    const float* in;
    Vec2i in_size;
    int out_width;
    float* out;
    VF_HOST_DEVICE void operator()(int i) const {
        out[i] = downsampleIntensityPixel(in, in_size, i % out_width, i / out_width);
    }
};

struct SobelPixels {
    const float* intensity;
    Vec2i size;
    Vec2f* gradient;
    VF_HOST_DEVICE void operator()(int i) const {
        gradient[i] = sobelGradientPixel(intensity, size, i % size.x, i / size.x);
    }
};

// Element i: model point i of the (model / step) grid, coloured from the intensity image.
struct ColorModelPoints {
    const Vec4f* model_points;
    int model_width;
    int step;
    int out_width;
    const float* intensity;
    Vec2i size;
    Mat4f T_rgb_world;
    Intrinsics rgb;
    ColorPoint* points;
    VF_HOST_DEVICE void operator()(int i) const {
        const int x = i % out_width, y = i / out_width;
        points[i] =
            colorPointFromModel(model_points[x * step + y * step * model_width], intensity, size, T_rgb_world, rgb);
    }
};

// Element i: the far-field point of pixel (x * step, y * step) of a keyframe's far depths, on the
// (size / step) grid.
struct FarFieldPoints {
    const float* far_depth;
    Vec2i depth_size;
    int step;
    int out_width;
    Intrinsics depth_camera;
    Mat4f T_world_camera;
    const float* intensity;
    const Vec2f* gradient;
    Vec2i size;
    Mat4f T_rgb_world;
    Intrinsics rgb;
    ColorPoint* points;
    float* gradient_sq;
    VF_HOST_DEVICE void operator()(int i) const {
        const int x = (i % out_width) * step, y = (i / out_width) * step;
        points[i] = farFieldPoint(far_depth[x + y * depth_size.x], x, y, depth_camera, T_world_camera, intensity,
                                  gradient, size, T_rgb_world, rgb, gradient_sq[i]);
    }
};

struct UnhiddenFarFieldPoints {
    const ColorPoint* points;
    const float* depth;
    Vec2i size;
    Mat4f T_camera_world;
    Intrinsics depth_camera;
    ColorPoint* out;
    VF_HOST_DEVICE void operator()(int i) const {
        out[i] = unhiddenFarFieldPoint(points[i], depth, size, T_camera_world, depth_camera);
    }
};

// The terms for the launchers' sumNormalEquations: element i is point i.
struct PhotometricTerms {
    const ColorPoint* points;
    const float* intensity;
    const Vec2f* gradient;
    Vec2i size;
    ColorTermParams params;
    VF_HOST_DEVICE bool operator()(int i, float J[6], float& residual) const {
        return photometricTerm(points[i], intensity, gradient, size, params, J, residual);
    }
};

struct PointIsColored {
    const ColorPoint* points;
    VF_HOST_DEVICE bool operator()(int i) const { return points[i].intensity >= 0.f; }
};

}  // namespace voxfuse
