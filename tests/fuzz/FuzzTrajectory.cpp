// TUM trajectories ("timestamp tx ty tz qx qy qz qw"): read or refused; what is read writes and
// reads back as many poses, each a rotation.

#include <cmath>
#include <cstdlib>

#include "FuzzInput.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/TrajectoryIO.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace voxfuse;
    const std::string path = fuzz::writeInput(data, size, "groundtruth.txt");
    std::vector<TimedPose> poses;
    try {
        poses = readTumTrajectory(path);
    } catch (const Error&) {
        return 0;
    }
    for (const TimedPose& p : poses)
        for (float v : p.T_world_camera.m)
            if (!std::isfinite(v)) std::abort();  // a pose the engines cannot use got through
    const std::string copy = fuzz::scratchFolder() + "/trajectory_written.txt";
    writeTumTrajectory(copy, poses);
    if (readTumTrajectory(copy).size() != poses.size()) std::abort();
    Mat4f T;
    if (!poses.empty()) interpolatePose(poses, poses.front().timestamp_s + 0.01, 0.02, T);
    return 0;
}
