#pragma once
// The Python pipeline: a MainEngine built from settings with the command line's names and defaults,
// fed NumPy frames, keeping what a script asks afterwards (trajectory, per-stage timings, summary).

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/io/TrajectoryIO.h"

namespace voxfuse::python {

// `voxfuse --help` names, same defaults (the voxel type too: s_rgb).
struct PipelineSettings {
    std::string voxel = "s_rgb";
    std::string index = "hash";
    std::string device = "cpu";
    float voxel_size = SceneParams{}.voxel_size_m;
    float mu = SceneParams{}.mu_m;
    int max_weight = SceneParams{}.max_weight;
    float min_depth = SceneParams{}.view_frustum_min_m;
    float max_depth = SceneParams{}.view_frustum_max_m;
    float depth_gap_tolerance = MainEngineSettings{}.depth_gap_tolerance;
    int max_blocks = kAutomaticBlockCount;  // 0: the engine chooses (automaticMaxBlockCount)
    int hash_buckets = VoxelBlockHashSettings{}.bucket_count;
    int hash_excess = VoxelBlockHashSettings{}.excess_entry_count;
    std::vector<int> volume_size{512, 512, 512};
    std::vector<int> volume_offset{-256, -256, 0};
    std::string tracker;  // "" = the default (ren)
    std::string tracker_config;
    std::string tracker_levels;
    std::vector<int> tracker_iterations;
    std::vector<float> tracker_max_distance;
    std::string label_update = "probabilistic";
    bool swap = false;
    int active_blocks = 0;
    std::string swap_file;
    int swap_blocks_per_frame = SwapSettings{}.blocks_per_frame;
    bool relocalise = RelocalisationSettings{}.enabled;
    int relocalise_candidates = RelocalisationSettings{}.candidates;
    float relocalise_max_speed = RelocalisationSettings{}.max_speed_m_per_s;
    float relocalise_min_color_correlation = RelocalisationSettings{}.min_color_correlation;

    // The engine's settings; ConfigError naming the setting when one is not valid.
    MainEngineSettings toEngineSettings() const;
    // The settings a map file fixes (voxel type, index and its settings, voxel size, mu), from `info`.
    void adopt(const MapFileInfo& info);
};

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
