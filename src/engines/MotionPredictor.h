#pragma once
// Constant-velocity prediction of a camera pose from the last two tracked frames (host side). A
// hand-held or robot camera keeps most of its motion from one frame to the next: starting the tracker
// from the predicted pose leaves it only the change of motion to find.

#include <algorithm>

#include "PoseUpdate.h"

namespace voxfuse {

class MotionPredictor {
public:
    // The pose to start from for a frame taken at `time_s`, the caller's pose being `T_given`: the
    // last motion, scaled to the time since the last frame, applied to `T_given`. No prediction
    // (T_given itself) unless T_given is the last recorded pose (nothing moved the camera in between:
    // a reset, a loaded map, a relocalisation), the last two frames were recorded, and the time since
    // the last frame is at most kMaxGapRatio frame intervals (after a longer gap the motion is unknown).
    Eigen::Matrix4d predict(const Mat4f& T_given, double time_s) const {
        const Eigen::Matrix4d given = pose::toEigenD(T_given);
        if (count_ < 2 || !std::equal(T_given.m, T_given.m + 16, last_f_.m)) return given;
        double ratio = 1.0;  // without timestamps, frames are taken to be evenly spaced
        const double interval = last_time_s_ - previous_time_s_;
        if (time_s > 0.0 && last_time_s_ > 0.0 && previous_time_s_ > 0.0 && interval > 0.0) ratio = (time_s - last_time_s_) / interval;
        if (!(ratio > 0.0 && ratio <= kMaxGapRatio)) return given;
        const Eigen::Matrix4d motion = previous_.inverse() * last_;  // in the last camera's frame
        const Eigen::AngleAxisd rotation(Eigen::Matrix3d(motion.topLeftCorner<3, 3>()));
        Eigen::Matrix4d scaled = Eigen::Matrix4d::Identity();
        scaled.topLeftCorner<3, 3>() = Eigen::AngleAxisd(rotation.angle() * ratio, rotation.axis()).toRotationMatrix();
        scaled.topRightCorner<3, 1>() = motion.topRightCorner<3, 1>() * ratio;
        return given * scaled;
    }

    // A frame tracked well at `time_s` (<= 0: no timestamp), with the pose handed back to the caller.
    void record(const Mat4f& T_world_camera, double time_s) {
        previous_ = last_;
        previous_time_s_ = last_time_s_;
        last_ = pose::toEigenD(T_world_camera);
        last_f_ = T_world_camera;
        last_time_s_ = time_s;
        count_ = count_ < 2 ? count_ + 1 : 2;
    }

    // The motion is unknown from here on (a failed frame, a reset).
    void forget() { count_ = 0; }

    static constexpr double kMaxGapRatio = 3.0;

private:
    Eigen::Matrix4d previous_ = Eigen::Matrix4d::Identity(), last_ = Eigen::Matrix4d::Identity();
    Mat4f last_f_ = Mat4f::identity();
    double previous_time_s_ = 0.0, last_time_s_ = 0.0;
    int count_ = 0;
};

}  // namespace voxfuse
