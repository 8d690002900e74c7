#pragma once
// The free view: a camera that starts at the tracked pose and is then moved by the mouse, orbiting a
// pivot point in front of where it started (left drag) and moving towards or away from it (wheel).

#include "voxfuse/core/Math.h"

namespace voxfuse::viewer {

class OrbitCamera {
public:
    // Starts the free view at `T_world_camera`, orbiting the point `pivot_distance_m` along its optical axis.
    void startAt(const Mat4f& T_world_camera, float pivot_distance_m);
    // Back to following the tracked camera.
    void stop() { active_ = false; }
    bool active() const { return active_; }

    // Mouse motion in pixels: horizontal turns about the world's vertical axis, vertical about the
    // camera's horizontal axis, both through the pivot.
    void orbit(double dx_pixels, double dy_pixels);
    // Wheel steps: positive moves closer to the pivot (never through it).
    void zoom(double steps);

    const Mat4f& pose() const { return T_world_camera_; }

private:
    bool active_ = false;
    Mat4f T_world_camera_ = Mat4f::identity();
    Vec3f pivot_world_{0.f, 0.f, 0.f};
    Vec3f up_world_{0.f, -1.f, 0.f};  // the first camera's "up" (camera y points down), which defines the world
};

}  // namespace voxfuse::viewer
