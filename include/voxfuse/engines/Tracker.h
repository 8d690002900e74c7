#pragma once
// Camera tracking: the pose of the current view, estimated against the model raycast from the previous
// pose (frame-to-model, as KinectFusion and InfiniTAM). Implementations: depth ICP, colour, robust
// refinement and combined RGB-D (TrackerSettings::kind); their host-side optimisation lives in
// src/engines, their per-pixel loops in src/cpu and their per-pixel terms in include/voxfuse/shared.

#include <memory>
#include <vector>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/engines/TrackerSettings.h"
#include "voxfuse/objects/RenderState.h"
#include "voxfuse/objects/TrackingState.h"
#include "voxfuse/objects/View.h"

namespace voxfuse {

// What one track() call did, per pyramid level (coarse to fine), for benchmarks and logs.
struct TrackerLevelStats {
    int width = 0, height = 0;  // image size of the level
    int iterations = 0;         // Gauss-Newton / LM iterations run
    double ms = 0.0;            // time spent on the level
    int inliers = 0;            // terms in the last iteration
    float rms_residual = 0.f;   // RMS of those terms (metres for depth, intensity for colour)
};
struct TrackerStats {
    double prepare_ms = 0.0;  // filtering and pyramids of the current frame (and model colours)
    double total_ms = 0.0;    // the whole track() call
    std::vector<TrackerLevelStats> levels;
};

// What a tracker reads beyond the frame's depth and colour and the model's points and normals, for the
// pipeline to provide (it names no tracker kinds).
struct TrackerInputs {
    bool far_depth = false;        // View::far_depth: the depths beyond the view frustum (far-field keyframes)
    bool model_intensity = false;  // RenderState::intensity of the model: the map's colour (colour aligned to it)
};

class Tracker {
public:
    virtual ~Tracker() = default;
    // Estimates the pose of `view`, starting from tracking_state.T_world_camera (the previous pose),
    // against the model raycast `model` (points/normals in world coordinates seen from
    // model.T_world_camera). Writes pose, quality, inlier_ratio, residual_m, condition and (depth
    // trackers) translation_constraint into tracking_state. Never throws for bad frames: reports
    // TrackingQuality::Failed instead and then leaves the pose as it was.
    //
    // Call it for every frame, the first one included: while there is no map yet (the model has no
    // surface and never had one since construction or reset()) the pose is kept and reported Good,
    // as that frame defines the map; once a map existed, an empty model is a failure. The colour
    // trackers also remember each frame's colour to colour the model at the next one.
    virtual void track(TrackingState& tracking_state, const View& view, const RenderState& model) = 0;
    // Forgets the previous frame and the map (after a map reset).
    virtual void reset() = 0;
    // The pose the last track() returned is not to be built on (the caller rejected it, or it was one
    // of several tries on one frame): no motion is predicted from it and no model coloured with it.
    virtual void forgetLastPose() = 0;
    virtual const TrackerStats& lastStats() const = 0;
    virtual const TrackerSettings& settings() const = 0;
    virtual TrackerInputs inputs() const = 0;
};

// The tracker `settings.kind` asks for (validated first: ConfigError when a setting is out of range),
// with its per-pixel work on `device` (its images and the model are read there); DeviceError in a build
// without CUDA.
std::unique_ptr<Tracker> makeTracker(const TrackerSettings& settings, Device device);

class LowLevelEngine;
// True when `model` holds a surface point and point/normal images of its camera's size: something
// to track against (counted by `low_level`, on its device).
bool hasTrackableSurface(const RenderState& model, LowLevelEngine& low_level);

// What the quality rules look at: the tracker's final full-resolution system and the estimated motion.
struct TrackingMeasures {
    int inliers = 0;
    float inlier_ratio = 0.f;
    float condition = 0.f;  // see TrackingState::condition
    float translation_constraint =
        1.f / 3.f;            // see TrackingState::translation_constraint (1/3: no depth terms to judge)
    float depth_rms_m = 0.f;  // RMS point-to-plane residual (0 when the tracker has no depth terms)
    float color_rms = 0.f;    // RMS intensity residual (0 when colour is not what the tracker minimised)
    float motion_m = 0.f;     // pose change from the previous pose
    float motion_deg = 0.f;
};
// The quality rules every tracker applies (thresholds in TrackerSettings).
TrackingQuality assessTrackingQuality(const TrackerSettings& settings, const TrackingMeasures& measures);

}  // namespace voxfuse
