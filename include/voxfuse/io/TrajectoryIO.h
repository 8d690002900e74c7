#pragma once
// Trajectories in the TUM RGB-D format: "timestamp tx ty tz qx qy qz qw", camera-to-world.

#include <string>
#include <vector>

#include "voxfuse/core/Math.h"

namespace voxfuse {

struct TimedPose {
    double timestamp_s = 0.0;
    Mat4f T_world_camera = Mat4f::identity();
};

// Throws ParseError naming file and line on a malformed line; '#' lines and blank lines are skipped.
std::vector<TimedPose> readTumTrajectory(const std::string& path);
void writeTumTrajectory(const std::string& path, const std::vector<TimedPose>& poses);
// `poses` with each pose replaced by the one of `T_world_camera` at its place (e.g. a trajectory at
// MainEngine::optimisedPoses); `poses` unchanged when the counts differ.
std::vector<TimedPose> withPoses(const std::vector<TimedPose>& poses, const std::vector<Mat4f>& T_world_camera);

// The pose at time t, interpolated (linear translation, slerp rotation) between the two samples around
// t when both lie within max_gap_s of it, or the nearest sample within max_gap_s. False when none fits.
// `poses` must be sorted by time.
bool interpolatePose(const std::vector<TimedPose>& poses, double t, double max_gap_s, Mat4f& T_world_camera);

}  // namespace voxfuse
