#pragma once
// Calibration of an RGB-D camera pair, as in InfiniTAM's calib.txt: both cameras' intrinsics, the
// rigid transform from RGB to depth camera coordinates, and how raw depth values become metres.

#include <cstdint>

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/Intrinsics.h"

namespace voxfuse {

// Converts a raw 16-bit depth sample into metres. A raw value of 0 always means "no measurement".
struct DisparityCalib {
    enum class Type : int {
        Kinect,  // Kinect v1 disparity: depth_m = 8 * k2 * fx_depth / (k1 - raw)
        Affine   // depth_m = a * raw + b (e.g. a = 1/5000 for TUM PNGs, 1/1000 for millimetres)
    };
    Type type = Type::Affine;
    float a = 0.001f;  // Kinect: k1; Affine: scale
    float b = 0.f;     // Kinect: k2; Affine: offset

    static DisparityCalib affine(float scale, float offset = 0.f) { return {Type::Affine, scale, offset}; }
    static DisparityCalib kinect(float k1, float k2) { return {Type::Kinect, k1, k2}; }

    // Returns metres, or 0 when the sample is invalid.
    VF_HOST_DEVICE float toMetres(std::uint16_t raw, float fx_depth) const {
        if (raw == 0) return 0.f;
        float depth_m;
        if (type == Type::Kinect) {
            const float d = a - float(raw);
            depth_m = d > 0.f ? 8.f * b * fx_depth / d : 0.f;
        } else {
            depth_m = a * float(raw) + b;
        }
        return depth_m > 0.f ? depth_m : 0.f;
    }
};

// Radial (k1, k2, k3) and tangential (p1, p2) lens distortion in the Brown-Conrady model that OpenCV
// and the Matlab toolbox use, on normalised image coordinates. All zero means an ideal pinhole: the
// images are used as they are. Sources deliver raw images; ThreadedImageSource can undistort them.
struct LensDistortion {
    float k1 = 0.f, k2 = 0.f, p1 = 0.f, p2 = 0.f, k3 = 0.f;

    bool any() const { return k1 != 0.f || k2 != 0.f || p1 != 0.f || p2 != 0.f || k3 != 0.f; }
};

struct RGBDCalib {
    Intrinsics rgb;
    Intrinsics depth;
    Mat4f T_depth_rgb = Mat4f::identity();  // maps RGB-camera coordinates to depth-camera coordinates
    DisparityCalib disparity;
    LensDistortion rgb_distortion;    // optional "distortion_rgb" line of calib.txt
    LensDistortion depth_distortion;  // optional "distortion_depth" line of calib.txt

    // Semantic label images show what the colour camera sees (segmentations are computed from colour),
    // or what the depth camera sees in a calibration without colour.
    bool labelsFromColor() const { return rgb.valid(); }
    const Intrinsics& labelCamera() const { return labelsFromColor() ? rgb : depth; }
    const LensDistortion& labelDistortion() const { return labelsFromColor() ? rgb_distortion : depth_distortion; }
};

}  // namespace voxfuse
