#pragma once
// Test helpers: exact views of analytic scenes (from apps/synth) turned into engine inputs.

#include <cmath>
#include <cstring>

#include "SyntheticScene.h"
#include "voxfuse/core/EigenInterop.h"
#include "voxfuse/io/RGBDFrame.h"
#include "voxfuse/objects/SceneParams.h"
#include "voxfuse/objects/View.h"

namespace voxfuse::test {

inline Intrinsics kinectIntrinsics(int width = 640, int height = 480) {
    const float s = float(width) / 640.f;
    return Intrinsics{width,
                      height,
                      525.f * s,
                      525.f * s,
                      (319.5f + 0.5f) * s - 0.5f,
                      (239.5f + 0.5f) * float(height) / 480.f - 0.5f};
}

inline synth::PinholeCamera toPinhole(const Intrinsics& in) {
    synth::PinholeCamera c;
    c.width = in.width;
    c.height = in.height;
    c.fx = in.fx;
    c.fy = in.fy;
    c.cx = in.cx;
    c.cy = in.cy;
    return c;
}

// A view with exact depth (and the scene's colours) of `scene` seen from T_world_camera.
inline View renderView(const synth::SyntheticScene& scene, const Intrinsics& intr, const Mat4f& T_world_camera,
                       bool with_color = true) {
    Eigen::Isometry3f pose;
    pose.matrix() = toEigen(T_world_camera);
    const synth::RenderedFrame frame = scene.render(toPinhole(intr), pose, 1);
    View view;
    view.calib.depth = view.calib.rgb = intr;
    view.calib.disparity = DisparityCalib::affine(0.001f);
    view.depth.resize(intr.size());
    std::memcpy(view.depth.host(), frame.depth.data(), frame.depth.size() * sizeof(float));
    if (with_color) {
        view.rgb.resize(intr.size());
        for (std::size_t i = 0; i < frame.rgb.size(); ++i)
            view.rgb.host()[i] = Vec4u8{(unsigned char)std::lround(255.f * frame.rgb[i].x()),
                                        (unsigned char)std::lround(255.f * frame.rgb[i].y()),
                                        (unsigned char)std::lround(255.f * frame.rgb[i].z()), 255};
    }
    return view;
}

// Camera at `eye` looking at `target` (OpenCV axes: x right, y down, z forward; world z up).
inline Mat4f lookAt(const Eigen::Vector3f& eye, const Eigen::Vector3f& target) {
    Eigen::Vector3f z = (target - eye).normalized();
    Eigen::Vector3f x = z.cross(Eigen::Vector3f::UnitZ());
    if (x.norm() < 1e-4f) x = Eigen::Vector3f::UnitX();
    x.normalize();
    const Eigen::Vector3f y = z.cross(x);
    Eigen::Matrix4f T = Eigen::Matrix4f::Identity();
    T.block<3, 1>(0, 0) = x;
    T.block<3, 1>(0, 1) = y;
    T.block<3, 1>(0, 2) = z;
    T.block<3, 1>(0, 3) = eye;
    return toMat4f(T);
}

// A view with classes too: `classes` classes in vertical stripes of the label image (half the view's
// resolution), moved by `shift` stripes, so that neighbouring voxels and frames disagree.
inline View labelledView(const synth::SyntheticScene& scene, const Intrinsics& intr, const Mat4f& T_world_camera,
                         int shift, int classes = 4) {
    View view = renderView(scene, intr, T_world_camera);
    view.labels.resize(Vec2i{intr.width / 2, intr.height / 2});
    for (int v = 0; v < view.labels.height(); ++v)
        for (int u = 0; u < view.labels.width(); ++u)
            view.labels.at(u, v) = ClassId(1 + (u * classes / view.labels.width() + shift) % classes);
    return view;
}

// The frame a source would deliver for `view`: depth in millimetres (affine 0.001), colour as is.
inline RGBDFrame toRgbdFrame(const View& view, int index) {
    RGBDFrame f;
    f.index = index;
    f.timestamp_s = index / 30.0;
    f.depth_raw.resize(view.depth.size());
    for (std::size_t i = 0; i < view.depth.pixelCount(); ++i)
        f.depth_raw.host()[i] = std::uint16_t(std::lround(view.depth.host()[i] * 1000.f));
    f.rgb.resize(view.rgb.size());
    for (std::size_t i = 0; i < view.rgb.pixelCount(); ++i) f.rgb.host()[i] = view.rgb.host()[i];
    return f;
}

// 1 cm voxels and a 4 cm band: small synthetic scenes fuse in milliseconds.
inline SceneParams centimetreSceneParams(float max_depth_m = 2.5f) {
    SceneParams p;
    p.voxel_size_m = 0.01f;
    p.mu_m = 0.04f;
    p.view_frustum_max_m = max_depth_m;
    return p;
}

}  // namespace voxfuse::test
