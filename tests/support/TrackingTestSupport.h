#pragma once
// Test helpers for the trackers: a perfect model raycast made from an exact view, pose perturbations
// and pose error measures.

#include <algorithm>
#include <cmath>

#include "SyntheticViews.h"
#include "voxfuse/core/EigenInterop.h"
#include "voxfuse/engines/LowLevelEngine.h"
#include "voxfuse/objects/RenderState.h"

namespace voxfuse::test {

// What an exact raycast of the scene from T_world_camera holds: the view's vertices in world
// coordinates, with normals from the vertex map (exact on planes).
inline RenderState modelFromView(const View& view, const Mat4f& T_world_camera) {
    auto low_level = makeLowLevelEngine(Device::CPU);
    Image<Vec4f> vertices, normals;
    low_level->computeVertexMap(view.depth, view.calib.depth, vertices);
    low_level->computeNormalMap(vertices, normals, 0.05f);
    RenderState model;
    model.resize(view.calib.depth);
    model.T_world_camera = T_world_camera;
    for (std::size_t i = 0; i < vertices.pixelCount(); ++i) {
        const Vec4f v = vertices.host()[i], n = normals.host()[i];
        const bool ok = v.w > 0.f && n.w > 0.f;
        const Vec3f p = transformPoint(T_world_camera, v.xyz()), nw = transformDirection(T_world_camera, n.xyz());
        model.points_world.host()[i] = ok ? Vec4f{p.x, p.y, p.z, 1.f} : Vec4f{0.f, 0.f, 0.f, 0.f};
        model.normals_world.host()[i] = ok ? Vec4f{nw.x, nw.y, nw.z, 1.f} : Vec4f{0.f, 0.f, 0.f, 0.f};
    }
    return model;
}

// A raycast that hit nothing (the state before the first frame is fused).
inline RenderState emptyModel(const Intrinsics& intrinsics) {
    RenderState model;
    model.resize(intrinsics);
    model.points_world.memory().fillBytes(0);
    model.normals_world.memory().fillBytes(0);
    return model;
}

// The pose after the camera rotates by `degrees` about `axis` (camera coordinates, through its centre)
// and then translates by `translation_m` (camera coordinates).
inline Mat4f moveInCamera(const Mat4f& T_world_camera, const Eigen::Vector3f& axis, float degrees,
                          const Eigen::Vector3f& translation_m) {
    Eigen::Matrix4f M = Eigen::Matrix4f::Identity();
    M.topLeftCorner<3, 3>() =
        Eigen::AngleAxisf(degrees * float(EIGEN_PI) / 180.f, axis.normalized()).toRotationMatrix();
    M.topRightCorner<3, 1>() = translation_m;
    return toMat4f(toEigen(T_world_camera) * M);
}

inline float translationErrorM(const Mat4f& a, const Mat4f& b) { return length(a.translation() - b.translation()); }

inline float rotationErrorDeg(const Mat4f& a, const Mat4f& b) {
    // Through a quaternion in double: acos of the trace cannot resolve angles below ~0.02 degrees in float.
    const Eigen::Matrix3d R =
        toEigen(a).topLeftCorner<3, 3>().cast<double>().transpose() * toEigen(b).topLeftCorner<3, 3>().cast<double>();
    const Eigen::AngleAxisd aa(R);
    return float(std::fabs(aa.angle()) * 180.0 / EIGEN_PI);
}

}  // namespace voxfuse::test
