#pragma once
// Recorded frames played in another order, with frames left out or their depth blanked: the gaps of a
// real camera (a dropped stretch of frames, a covered lens) made from a recording with ground truth.

#include <cstring>
#include <vector>

#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/eval/TrajectoryError.h"
#include "voxfuse/io/ImageSource.h"

namespace voxfuse::test {

// One step of an edited sequence: which recorded frame, and whether its depth is replaced by zeros.
struct PlayedFrame {
    int frame = 0;
    bool blank_depth = false;
};

// Every frame of a source, in memory, with its ground truth.
inline std::vector<RGBDFrame> readAllFrames(ImageSource& source) {
    std::vector<RGBDFrame> frames(1);
    while (source.next(frames.back())) frames.emplace_back();
    frames.pop_back();
    return frames;
}

template <class T>
void copyImage(const Image<T>& from, Image<T>& to) {
    to.resize(from.size());
    if (!from.empty()) std::memcpy(static_cast<void*>(to.host()), from.host(), from.pixelCount() * sizeof(T));
}

struct PlayedResult {
    PlayedFrame played;
    FrameResult result;
    bool has_ground_truth = false;
    Mat4f T_world_camera_gt = Mat4f::identity();  // in the source's ground-truth frame
};

// Runs `engine` over `script` (the played frames get consecutive indices and their recorded timestamps).
inline std::vector<PlayedResult> play(MainEngine& engine, const std::vector<RGBDFrame>& frames,
                                      const std::vector<PlayedFrame>& script) {
    std::vector<PlayedResult> out;
    RGBDFrame frame;
    for (const PlayedFrame& p : script) {
        const RGBDFrame& recorded = frames.at(std::size_t(p.frame));
        copyImage(recorded.depth_raw, frame.depth_raw);
        copyImage(recorded.rgb, frame.rgb);
        if (p.blank_depth) frame.depth_raw.memory().fillBytes(0);
        frame.index = int(out.size());
        frame.timestamp_s = recorded.timestamp_s;
        frame.has_ground_truth = recorded.has_ground_truth;
        frame.T_world_camera_gt = recorded.T_world_camera_gt;
        out.push_back({p, engine.processFrame(frame, nullptr), frame.has_ground_truth, frame.T_world_camera_gt});
    }
    return out;
}

// The frames with a pose (tracked or relocalised), for the trajectory error.
inline std::vector<TimedPose> posedTrajectory(const std::vector<PlayedResult>& run,
                                              const std::vector<RGBDFrame>& frames) {
    std::vector<TimedPose> trajectory;
    for (const PlayedResult& r : run)
        if (r.result.status != TrackingStatus::Lost)
            trajectory.push_back({frames[std::size_t(r.played.frame)].timestamp_s, r.result.T_world_camera});
    return trajectory;
}

// Position error of each frame with a pose and ground truth, after the ATE alignment of `error`.
inline std::vector<float> alignedErrorsM(const std::vector<PlayedResult>& run, const TrajectoryError& error) {
    std::vector<float> errors(run.size(), -1.f);
    for (std::size_t i = 0; i < run.size(); ++i) {
        if (run[i].result.status == TrackingStatus::Lost || !run[i].has_ground_truth) continue;
        const Mat4f T_truth_camera = error.T_truth_estimate * run[i].result.T_world_camera;
        errors[i] = length(T_truth_camera.translation() - run[i].T_world_camera_gt.translation());
    }
    return errors;
}

}  // namespace voxfuse::test
