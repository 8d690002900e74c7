#include "OrbitCamera.h"

#include <algorithm>
#include <cmath>

namespace voxfuse::viewer {
namespace {

constexpr float kRadiansPerPixel = 0.005f;
constexpr float kZoomPerStep = 0.9f;  // each wheel step keeps this fraction of the distance
constexpr float kMinPivotDistanceM = 0.05f;

// Rotation by `angle` about the unit `axis` (Rodrigues), as a 4x4 with no translation.
Mat4f rotationAbout(Vec3f axis, float angle) {
    const float c = std::cos(angle), s = std::sin(angle), t = 1.f - c;
    const Vec3f a = normalize(axis);
    Mat4f R = Mat4f::identity();
    R(0, 0) = t * a.x * a.x + c;
    R(0, 1) = t * a.x * a.y - s * a.z;
    R(0, 2) = t * a.x * a.z + s * a.y;
    R(1, 0) = t * a.x * a.y + s * a.z;
    R(1, 1) = t * a.y * a.y + c;
    R(1, 2) = t * a.y * a.z - s * a.x;
    R(2, 0) = t * a.x * a.z - s * a.y;
    R(2, 1) = t * a.y * a.z + s * a.x;
    R(2, 2) = t * a.z * a.z + c;
    return R;
}

Mat4f translation(Vec3f t) {
    Mat4f T = Mat4f::identity();
    T(0, 3) = t.x;
    T(1, 3) = t.y;
    T(2, 3) = t.z;
    return T;
}

}  // namespace

void OrbitCamera::startAt(const Mat4f& T_world_camera, float pivot_distance_m) {
    T_world_camera_ = T_world_camera;
    pivot_world_ = transformPoint(T_world_camera, {0.f, 0.f, std::max(pivot_distance_m, kMinPivotDistanceM)});
    active_ = true;
}

void OrbitCamera::orbit(double dx_pixels, double dy_pixels) {
    const Vec3f camera_x_world = transformDirection(T_world_camera_, {1.f, 0.f, 0.f});
    // Dragging right swings the camera to the left around the pivot, so the model turns with the mouse.
    const Mat4f R = rotationAbout(up_world_, float(dx_pixels) * kRadiansPerPixel) *
                    rotationAbout(camera_x_world, float(dy_pixels) * kRadiansPerPixel);
    T_world_camera_ = translation(pivot_world_) * R * translation(-pivot_world_) * T_world_camera_;
}

void OrbitCamera::zoom(double steps) {
    const Vec3f centre = T_world_camera_.translation();
    const float distance = length(pivot_world_ - centre);
    const float new_distance = std::max(kMinPivotDistanceM, distance * std::pow(kZoomPerStep, float(steps)));
    const Vec3f forward = transformDirection(T_world_camera_, {0.f, 0.f, 1.f});
    const Vec3f moved = centre + forward * (distance - new_distance);
    T_world_camera_(0, 3) = moved.x;
    T_world_camera_(1, 3) = moved.y;
    T_world_camera_(2, 3) = moved.z;
}

}  // namespace voxfuse::viewer
