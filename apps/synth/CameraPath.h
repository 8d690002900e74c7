// Smooth hand-held camera trajectory for the synthetic room: the camera walks
// along an ellipse around the objects at head height, always looking at them,
// with small sinusoidal shake in position and rotation.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace voxfuse::synth {

struct CameraPathParams {
    Eigen::Vector2f orbitCenter{0.1f, 0.05f};   // world xy (m)
    Eigen::Vector2f orbitRadii{1.7f, 1.35f};    // semi-axes along world x, y (m)
    float startAngleDeg = 180.0f;               // start on the -x side of the room
    float speed = 0.3f;                         // mean walking speed along the orbit (m/s)
    float height = 1.45f;                       // mean camera height (m)
    float heightSwing = 0.08f;                  // slow up/down motion (m)
    Eigen::Vector3f target{0.1f, 0.05f, 0.6f};  // point the camera looks at (m)
    float shake = 1.0f;                         // scales hand-held shake; 0 = smooth
};

class CameraPath {
public:
    using Params = CameraPathParams;

    static constexpr double kFps = 30.0;

    CameraPath() = default;
    explicit CameraPath(const Params& params) : params_(params) {}

    // T_world_camera (camera-to-world, OpenCV camera axes) at time t.
    Eigen::Isometry3f poseAt(double seconds) const;
    Eigen::Isometry3f pose(int frame) const { return poseAt(frame / kFps); }

    // Camera at eye looking at target, image "up" towards world up.
    static Eigen::Isometry3f lookAt(const Eigen::Vector3f& eye, const Eigen::Vector3f& target,
                                    const Eigen::Vector3f& worldUp = Eigen::Vector3f::UnitZ());

    const Params& params() const { return params_; }

private:
    Params params_{};
};

// Walking down SyntheticScene::corridor(length) and back: `frames` frames at 30 fps, out along +x
// at walking pace, a turn on the spot at the far end, and back, looking where it goes with a little
// sway. The start is revisited at the end, so blocks swapped out on the way come back.
class CorridorWalk {
public:
    CorridorWalk(float length_m, int frames) : length_m_(length_m), frames_(frames) {}
    Eigen::Isometry3f pose(int frame) const;

private:
    float length_m_;
    int frames_;
};

}  // namespace voxfuse::synth
