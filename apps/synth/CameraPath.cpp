#include "CameraPath.h"

#include <algorithm>
#include <cmath>

namespace voxfuse::synth {
namespace {

constexpr double kTwoPi = 6.283185307179586;

// Sum of two sines with incommensurate frequencies: looks irregular, stays smooth.
double shake(double t, double a1, double f1, double p1, double a2, double f2, double p2) {
    return a1 * std::sin(kTwoPi * f1 * t + p1) + a2 * std::sin(kTwoPi * f2 * t + p2);
}

}  // namespace

Eigen::Isometry3f CameraPath::lookAt(const Eigen::Vector3f& eye, const Eigen::Vector3f& target,
                                     const Eigen::Vector3f& worldUp) {
    const Eigen::Vector3f forward = (target - eye).normalized();
    const Eigen::Vector3f right = forward.cross(worldUp).normalized();
    const Eigen::Vector3f down = forward.cross(right);
    Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
    T.linear().col(0) = right;
    T.linear().col(1) = down;
    T.linear().col(2) = forward;
    T.translation() = eye;
    return T;
}

Eigen::Isometry3f CameraPath::poseAt(double t) const {
    const Params& p = params_;
    const double meanRadius = 0.5 * (p.orbitRadii.x() + p.orbitRadii.y());
    const double angle = p.startAngleDeg * kTwoPi / 360.0 + p.speed * t / meanRadius;
    const double s = p.shake;

    // Walking along the ellipse; hand shake of ~1 cm at 0.7-2.3 Hz on top.
    const Eigen::Vector3d eye(
        p.orbitCenter.x() + p.orbitRadii.x() * std::cos(angle) + s * shake(t, 0.010, 0.9, 0.3, 0.005, 1.7, 1.1),
        p.orbitCenter.y() + p.orbitRadii.y() * std::sin(angle) + s * shake(t, 0.010, 0.7, 2.0, 0.005, 1.9, 0.5),
        p.height + p.heightSwing * std::sin(kTwoPi * 0.11 * t) + s * shake(t, 0.008, 1.1, 1.3, 0.004, 2.3, 2.2));

    // The gaze drifts slowly over the objects and jitters a little.
    const Eigen::Vector3d target(
        p.target.x() + 0.25 * std::sin(kTwoPi * 0.07 * t) + s * shake(t, 0.03, 0.5, 0.0, 0.01, 1.3, 0.7),
        p.target.y() + 0.20 * std::sin(kTwoPi * 0.05 * t + 1.0) + s * shake(t, 0.03, 0.37, 1.0, 0.01, 1.5, 2.4),
        p.target.z() + 0.10 * std::sin(kTwoPi * 0.09 * t + 2.0) + s * shake(t, 0.02, 0.6, 2.0, 0.01, 1.1, 0.2));

    Eigen::Isometry3f T = lookAt(eye.cast<float>(), target.cast<float>());
    const double rollDeg = s * shake(t, 1.5, 0.45, 0.4, 0.7, 1.3, 1.9);  // wrist roll
    T.linear() =
        T.linear() *
        Eigen::AngleAxisf(static_cast<float>(rollDeg * kTwoPi / 360.0), Eigen::Vector3f::UnitZ()).toRotationMatrix();
    return T;
}

}  // namespace voxfuse::synth

namespace voxfuse::synth {

Eigen::Isometry3f CorridorWalk::pose(int frame) const {
    // Out over 45% of the frames, turn over 10%, back over 45%; smooth (cosine) speed within each.
    const double u = frames_ > 1 ? double(frame) / double(frames_ - 1) : 0.0;
    const double x0 = 0.6, x1 = double(length_m_) - 1.6;
    auto ease = [](double f) { return 0.5 - 0.5 * std::cos(kTwoPi * 0.5 * std::clamp(f, 0.0, 1.0)); };
    double x, heading;
    if (u < 0.45) {
        x = x0 + (x1 - x0) * ease(u / 0.45);
        heading = 0.0;
    } else if (u < 0.55) {
        x = x1;
        heading = kTwoPi * 0.5 * ease((u - 0.45) / 0.1);
    } else {
        x = x1 - (x1 - x0) * ease((u - 0.55) / 0.45);
        heading = kTwoPi * 0.5;
    }
    const double t = double(frame) / CameraPath::kFps;
    const double sway = 0.25 * std::sin(kTwoPi * 0.13 * t);  // the gaze wanders over the walls (rad)
    const Eigen::Vector3d eye(x, 0.15 * std::sin(kTwoPi * 0.07 * t), 1.5 + 0.05 * std::sin(kTwoPi * 0.23 * t));
    const Eigen::Vector3d gaze(std::cos(heading + sway), std::sin(heading + sway), -0.25);
    return CameraPath::lookAt(eye.cast<float>(), (eye + gaze).cast<float>());
}

}  // namespace voxfuse::synth
