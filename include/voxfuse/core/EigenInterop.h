#pragma once
// Host-side conversions between the device-agnostic POD types and Eigen.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "voxfuse/core/Math.h"

namespace voxfuse {

inline Mat4f toMat4f(const Eigen::Matrix4f& e) {
    Mat4f m;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m(r, c) = e(r, c);
    return m;
}
inline Eigen::Matrix4f toEigen(const Mat4f& m) {
    Eigen::Matrix4f e;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) e(r, c) = m(r, c);
    return e;
}
inline Eigen::Vector3f toEigen(Vec3f v) { return {v.x, v.y, v.z}; }
inline Vec3f toVec3f(const Eigen::Vector3f& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace voxfuse
