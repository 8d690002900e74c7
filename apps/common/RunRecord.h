#pragma once
// What a run of the CLI measured, frame by frame, and how it is written to the output folder.

#include <string>
#include <vector>

#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/eval/TrajectoryError.h"
#include "voxfuse/io/TrajectoryIO.h"

namespace voxfuse::app {

struct FrameRecord {
    int index = 0;
    double timestamp_s = 0.0;
    FrameResult result;
};

struct RunRecord {
    std::string source;
    MainEngineSettings settings;
    std::vector<FrameRecord> frames;  // every processed frame
    std::vector<TimedPose> trajectory;
    int frames_without_pose = 0;  // skipped: --poses groundtruth but no ground truth for the frame
    int frames_unreadable = 0;    // skipped: the source could not read them
    int frames_dropped = 0;       // live input: dropped by the reader thread while the engine lagged
    // Depth samples above the maximum their file declares or that the calibration maps to no depth (read
    // as no measurement), colour samples above their file's maximum (read as full intensity), and the
    // frames with any.
    long long depth_samples_out_of_range = 0;
    long long color_samples_out_of_range = 0;
    int frames_with_samples_out_of_range = 0;
    bool has_labels = false;     // a label image stream was attached
    int frames_with_labels = 0;  // frames a label image was found for
    double wall_s = 0.0;
    double peak_rss_mb = 0.0;
    double scene_mb = 0.0;
    double mesh_ms = -1.0;             // extracting the mesh at the end (-1: none asked for)
    AllocationStats allocation;        // the index at the end (hash only)
    bool tracked = false;              // poses came from the tracker (not ground truth)
    std::string map_loaded;            // the map file the run continued, if any
    std::string map_saved;             // the map file the run wrote, if any
    bool interrupted = false;          // stopped early by Ctrl-C or SIGTERM (the outputs hold the frames done)
    std::vector<std::string> outputs;  // the files this run wrote in its output folder (summary.json last)
    bool has_trajectory_error = false;
    TrajectoryError trajectory_error;  // against the source's ground truth, when it has one
    // With submaps: `trajectory` holds the poses at the submaps' optimised poses, this one the poses as
    // tracked (trajectory_online.txt), with its own error.
    int submaps = 1;
    std::vector<LoopClosure> loop_closures;  // frame: index into `frames`
    PoseGraphSolveStats pose_graph;          // the solves of the whole run, on the optimiser's thread
    std::vector<TimedPose> trajectory_online;
    TrajectoryError trajectory_error_online;
};

// Frames whose tracking was poor / failed (failed frames are not fused).
int countQuality(const RunRecord& run, TrackingQuality quality);
// Frames that were tracking / lost / relocalised, and those on which relocalisation was tried.
int countStatus(const RunRecord& run, TrackingStatus status);
int countRelocalisationAttempts(const RunRecord& run);

int countFused(const RunRecord& run);
// Why the run added nothing to the map, or "" when it did: no frame was fused, or (a hash map) the frames
// fused left it without a block, so no depth sample lay in the view frustum. Interrupted runs and runs
// without frames (a map written out alone) are not judged.
std::string nothingFusedReason(const RunRecord& run);

double medianTotalMs(const RunRecord& run);
double framesPerSecond(const RunRecord& run);

// DIR/timings.json: per-stage ms of every frame and the medians.
void writeTimingsJson(const std::string& path, const RunRecord& run);
// DIR/summary.json: frames, median_ms, fps, peak_rss_mb, the settings used, whether the run was
// interrupted and the files it wrote.
void writeSummaryJson(const std::string& path, const RunRecord& run);
// The one-screen summary printed at the end.
std::string summaryText(const RunRecord& run, const std::string& out_dir);

}  // namespace voxfuse::app
