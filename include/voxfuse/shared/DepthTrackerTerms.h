#pragma once
// One point-to-plane ICP term (section 4.1 of the InfiniTAM report, after KinectFusion): a vertex of
// the current depth frame, moved to the world by the pose estimate, is associated projectively with
// the model raycast (the pixel it falls on in the raycast camera), and its residual is its distance to
// the model point's tangent plane. Pairs too far apart or with too different normals are outliers.

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/Intrinsics.h"
#include "voxfuse/shared/LowLevel.h"

namespace voxfuse {

// What every pixel of one ICP iteration shares.
struct DepthTermParams {
    Mat4f T_world_camera;  // the pose estimate being refined (current depth camera to world)
    Mat4f T_model_world;   // world to the camera the model was raycast from
    Intrinsics model;      // that camera (the raycast images are model.width x model.height)
    float max_distance_m;  // pairs farther apart (Euclidean) are outliers
    float min_normal_cos;  // pairs whose normals make a larger angle are outliers; < -1 disables the test
};

// R^T d for the rotation R of a rigid transform: a world direction in camera coordinates.
VF_HOST_DEVICE inline Vec3f rotateInverse(const Mat4f& T, Vec3f d) {
    return {T.m[0] * d.x + T.m[4] * d.y + T.m[8] * d.z, T.m[1] * d.x + T.m[5] * d.y + T.m[9] * d.z,
            T.m[2] * d.x + T.m[6] * d.y + T.m[10] * d.z};
}

// The nearest raycast pixel to a model-camera point, or -1 when it falls outside the image or behind
// the camera.
VF_HOST_DEVICE inline int modelPixelIndex(const Intrinsics& model, Vec3f p_model) {
    if (p_model.z <= 1e-6f) return -1;
    return model.nearestPixelIndex(model.project(p_model));
}

// The point-to-plane term of one frame vertex (camera coordinates, w = 1 when valid) with its normal
// (w = 1 when valid; with the normal test on, vertices without a normal are rejected). Writes the residual
// r = n_model . (T * vertex - p_model) in metres and its Jacobian J = dr/dx for the update
// T * exp(x), x = (omega, v) in camera coordinates: J = [vertex x n_c, n_c] with n_c = R^T n_model.
// Returns false when the vertex has no acceptable model correspondence.
VF_HOST_DEVICE inline bool pointToPlaneTerm(Vec4f vertex, Vec4f normal, const Vec4f* model_points,
                                            const Vec4f* model_normals, const DepthTermParams& p, float J[6],
                                            float& residual) {
    if (vertex.w <= 0.f) return false;
    const Vec3f v = vertex.xyz();
    const Vec3f q = transformPoint(p.T_world_camera, v);
    const int i = modelPixelIndex(p.model, transformPoint(p.T_model_world, q));
    if (i < 0) return false;
    const Vec4f m = model_points[i], n = model_normals[i];
    if (m.w <= 0.f || n.w <= 0.f) return false;
    const Vec3f d = q - m.xyz();
    if (dot(d, d) > p.max_distance_m * p.max_distance_m) return false;
    const Vec3f n_c = rotateInverse(p.T_world_camera, n.xyz());
    if (p.min_normal_cos >= -1.f) {
        if (normal.w <= 0.f || dot(normal.xyz(), n_c) < p.min_normal_cos) return false;
    }
    residual = dot(n.xyz(), d);
    const Vec3f vxn = cross(v, n_c);
    J[0] = vxn.x;
    J[1] = vxn.y;
    J[2] = vxn.z;
    J[3] = n_c.x;
    J[4] = n_c.y;
    J[5] = n_c.z;
    return true;
}

// The terms of one level for the launchers' sumNormalEquations: element i is the level's packed
// point i (DepthFrameLevel).
struct PointToPlaneTerms {
    const Vec4f* vertices;
    const Vec4f* normals;
    const Vec4f* model_points;
    const Vec4f* model_normals;
    DepthTermParams params;
    VF_HOST_DEVICE bool operator()(int i, float J[6], float& residual) const {
        return pointToPlaneTerm(vertices[i], normals[i], model_points, model_normals, params, J, residual);
    }
};

}  // namespace voxfuse
