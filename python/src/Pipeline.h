#pragma once
// The Python pipeline: a MainEngine built from the settings table (the command line's names and defaults),
// fed NumPy frames, keeping what a script asks afterwards (trajectory, per-stage timings, summary).

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/engines/PipelineSettings.h"
#include "voxfuse/io/TrajectoryIO.h"

namespace voxfuse::python {

using voxfuse::PipelineSettings;  // the settings table (engines/PipelineSettings.h)

struct StageTimes {
    std::vector<double> ms;
};

class Pipeline {
public:
    Pipeline(const RGBDCalib& calib, const PipelineSettings& settings);

    // One frame (the arrays already checked and copied into `frame`). Called without the GIL.
    FrameResult process(const RGBDFrame& frame, const Mat4f* T_world_camera_given);
    // The frame's ground-truth pose in the world of this run (the first such frame's camera, or the
    // origin a loaded map gives), as `voxfuse --poses groundtruth` places frames. ConfigError without one.
    Mat4f groundTruthPose(const RGBDFrame& frame);

    MainEngine& engine() { return *engine_; }
    const RGBDCalib& calib() const { return calib_; }
    const PipelineSettings& settings() const { return settings_; }
    const std::vector<TimedPose>& trajectory() const { return trajectory_; }
    // With submaps: the trajectory's frames at the submaps' optimised poses (waits for the pose graph);
    // without, the trajectory itself.
    std::vector<TimedPose> optimisedTrajectory();
    const std::map<std::string, StageTimes>& stageTimes() const { return stage_times_; }
    int framesProcessed() const { return frames_; }
    int framesFused() const { return fused_; }
    int framesFailed() const { return failed_; }
    int framesPoor() const { return poor_; }
    int framesLost() const { return lost_; }
    int relocalisationAttempts() const { return relocalisation_attempts_; }
    int relocalisations() const { return relocalisations_; }
    RGBDFrame& frameBuffer() { return frame_; }
    void reset();
    // One call at a time: the GIL is released while the engine works, so another Python thread could
    // otherwise enter the same pipeline. Never waits (waiting while holding the GIL could deadlock):
    // voxfuse::Error naming `call` when the pipeline is busy.
    std::unique_lock<std::mutex> claim(const char* call);

private:
    RGBDCalib calib_;
    PipelineSettings settings_;
    std::unique_ptr<MainEngine> engine_;
    RGBDFrame frame_;                    // reused: its images keep their memory between frames
    std::vector<TimedPose> trajectory_;  // the frames with a pose: a lost frame has none (as the CLI's trajectory.txt)
    std::map<std::string, StageTimes> stage_times_;
    int frames_ = 0, fused_ = 0, failed_ = 0, poor_ = 0;
    int lost_ = 0, relocalisation_attempts_ = 0, relocalisations_ = 0;
    std::mutex busy_;
    bool have_origin_ = false;
    Mat4f T_origin_world_ = Mat4f::identity();
};

}  // namespace voxfuse::python
