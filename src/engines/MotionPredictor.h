#pragma once
// Constant-velocity prediction of a camera pose from the last two tracked frames (host side). A
// hand-held or robot camera keeps most of its motion from one frame to the next: starting the tracker
// from the predicted pose leaves it only the change of motion to find.

#include <algorithm>

#include "PoseUpdate.h"
#include "voxfuse/objects/FrameClock.h"

namespace voxfuse {

class MotionPredictor {
public:
    // The pose to start from for a frame taken at `now`, the caller's pose being `T_given`: the last
    // motion, scaled to the time since the last frame, applied to `T_given`. No prediction (T_given
    // itself) unless T_given is the last recorded pose (nothing moved the camera in between: a reset, a
    // loaded map, a relocalisation), the last two recorded frames are different frames, and `now` is
    // later than the last one by at most kMaxGapRatio of their interval (after a longer gap the motion
    // is unknown; the same frame tracked again, as relocalisation does, has no motion to predict).
    Eigen::Matrix4d predict(const Mat4f& T_given, FrameClock now) const {
        const Eigen::Matrix4d given = pose::toEigenD(T_given);
        if (count_ < 2 || !std::equal(T_given.m, T_given.m + 16, last_f_.m)) return given;
        const double ratio = elapsedRatio(now);
        if (!(ratio > 0.0 && ratio <= kMaxGapRatio)) return given;
        const Eigen::Matrix4d motion = previous_.inverse() * last_;  // in the last camera's frame
        const Eigen::AngleAxisd rotation(Eigen::Matrix3d(motion.topLeftCorner<3, 3>()));
        Eigen::Matrix4d scaled = Eigen::Matrix4d::Identity();
        scaled.topLeftCorner<3, 3>() = Eigen::AngleAxisd(rotation.angle() * ratio, rotation.axis()).toRotationMatrix();
        scaled.topRightCorner<3, 1>() = motion.topRightCorner<3, 1>() * ratio;
        return given * scaled;
    }

    // A frame tracked well at `now`, with the pose handed back to the caller. The same frame recorded
    // again (tracked once more from another start) replaces its pose.
    void record(const Mat4f& T_world_camera, FrameClock now) {
        if (count_ == 0 || !sameFrame(now, last_time_)) {
            previous_ = last_;
            previous_time_ = last_time_;
            count_ = count_ < 2 ? count_ + 1 : 2;
        }
        last_ = pose::toEigenD(T_world_camera);
        last_f_ = T_world_camera;
        last_time_ = now;
    }

    // The motion is unknown from here on (a failed frame, a rejected pose, a reset).
    void forget() { count_ = 0; }

    static constexpr double kMaxGapRatio = 3.0;

private:
    static bool sameFrame(FrameClock a, FrameClock b) { return a.timestamp_s == b.timestamp_s && a.index == b.index; }

    // (now - last) / (last - previous) (secondsBetween: timestamps, else frame indices); 0 when either
    // span is unknown or not forward in time.
    double elapsedRatio(FrameClock now) const {
        const double interval = secondsBetween(previous_time_, last_time_), elapsed = secondsBetween(last_time_, now);
        return interval > 0.0 && elapsed > 0.0 ? elapsed / interval : 0.0;
    }

    Eigen::Matrix4d previous_ = Eigen::Matrix4d::Identity(), last_ = Eigen::Matrix4d::Identity();
    Mat4f last_f_ = Mat4f::identity();
    FrameClock previous_time_, last_time_;
    int count_ = 0;
};

}  // namespace voxfuse
