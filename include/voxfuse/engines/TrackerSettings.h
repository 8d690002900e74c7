#pragma once
// Settings of the camera trackers, with their defaults, and the "key = value" settings file that
// overrides them (see parseTrackerSettingsFile for the keys).

#include <string>
#include <variant>
#include <vector>

#include "voxfuse/shared/RobustKernel.h"

namespace voxfuse {

enum class TrackerKind {
    Icp,    // depth only: point-to-plane ICP against the model raycast, coarse to fine
    Color,  // colour only: photometric alignment of model points (Levenberg-Marquardt)
    Ren,    // ICP with a robust (Tukey) kernel on every level: outliers weigh alike at every resolution
    Rgbd    // ren's robust depth residuals and colour residuals in one Gauss-Newton system
};
const char* toString(TrackerKind kind);
TrackerKind parseTrackerKind(const std::string& name);  // "icp", "color", "ren", "rgbd"; ConfigError otherwise

// Which pose parameters a pyramid level solves for (InfiniTAM's level types).
enum class LevelMotion : char {
    Rotation = 'r',     // rotation only: cheap, robust first guess on coarse images
    Translation = 't',  // translation only
    Both = 'b'          // full 6-DoF
};

struct TrackerLevel {
    LevelMotion motion = LevelMotion::Both;
    int max_iterations = 10;
    float max_distance_m = 0.1f;  // ICP outlier threshold on the point-to-model distance
    int pixel_step = 1;           // ICP terms from every pixel_step-th row and column of the level
};

// The defaults were chosen on recorded and synthetic sequences (docs/BENCHMARKS.md has their
// accuracy and speed) and are kept only where they hold on all of them, not tuned to one recording.
// The normal test is what lets an 8 cm / 8 degree jump converge.
struct TrackerSettings {
    // rgbd: ren's depth terms plus colour aligned to the map's fused colours. Where depth leaves a
    // motion weakly constrained (a corridor, a wall, a round object) the map's texture pins it, and
    // the map holds still while the estimate drifts. It tracks in about twice ren's time on the CPU.
    // With a voxel type without colour it aligns to the previous frame's colours; without a colour
    // image it is ren.
    TrackerKind kind = TrackerKind::Rgbd;
    // Pyramid levels, COARSE TO FINE: with n levels, levels[i] works on images downsampled by
    // 2^(n-1-i) (the last level is full resolution). Settings file: levels, iterations, max_distance_m.
    // The finest level takes every second row and column: the model it is aligned to is raycast at
    // half resolution (MainEngineSettings::tracking_raycast_downsample), so four of its pixels met one
    // model pixel, and the bilateral filter had already made them alike: a quarter of the terms gives
    // the same poses in a third of the level's time.
    std::vector<TrackerLevel> levels = {
        {LevelMotion::Both, 10, 0.10f, 1},  // 160x120
        {LevelMotion::Both, 10, 0.05f, 1},  // 320x240
        {LevelMotion::Both, 10, 0.02f, 2},  // 640x480, every second pixel in x and y
    };
    // Frame and model normals further apart than this reject the pair; 180 switches the test off.
    float max_normal_angle_deg = 30.f;
    // A level stops iterating when an update rotates less than this AND translates less than this;
    // a level downsampled by 2^k stops at 2^k times these (its pixels are that much larger, and the
    // finer levels refine what it leaves, so the coarse levels need fewer iterations for the same poses).
    float min_rotation_step_rad = 1e-4f;
    float min_translation_step_m = 1e-4f;
    // Stretch a Gauss-Newton step that continues the one before it by what the geometric series of
    // the remaining steps adds (see pose::StepExtrapolation): the same optimum in fewer iterations.
    // Only while the depth terms pin every translation (poor_translation_constraint below).
    bool extrapolate_steps = true;
    // Start from the pose the last two frames' motion predicts (constant velocity, scaled to the time
    // between frames) instead of the last pose: the tracker then only corrects the change of motion.
    bool predict_motion = true;
    // Edge-preserving smoothing of the depth before the pyramid is built (KinectFusion's bilateral filter).
    bool bilateral_filter = true;
    // Normals of the frame are computed only between neighbours closer than this (metres at full
    // resolution, doubled per coarser level): larger gaps are depth edges.
    float max_normal_edge_m = 0.05f;
    // Frame depths beyond this take no part in depth tracking (icp, ren, rgbd) but are still fused;
    // 0: every depth the view keeps. A sensor's far depths are its noisiest, and leaving them out can
    // help a depth-only tracker where the near scene holds enough structure. Off by default: which
    // depths are too noisy depends on the sensor, and far surfaces are what pin the motion along a
    // corridor or across a hall.
    float max_tracking_depth_m = 0.f;

    // ren and rgbd: the robust cost of every level's depth terms. One cost for all levels gives every
    // level the same optimum: with a kernel on the finest level only, the coarse levels converged to
    // poses that outliers had pulled away, and the finest level spent most of its iterations crawling
    // back.
    RobustKernel robust_kernel = RobustKernel::Tukey;
    float robust_scale_m = 0.01f;  // Tukey: residuals beyond this get no weight

    // color and rgbd: model points are taken every color_point_step pixels in x and y (2: every 4th
    // point, as InfiniTAM); photometric residuals are intensities in [0, 1].
    int color_point_step = 2;
    RobustKernel color_kernel = RobustKernel::Huber;
    float color_kernel_scale = 0.1f;
    // rgbd: weight of a squared photometric residual against a squared point-to-plane one, per term
    // (the colour sum is scaled to the number of depth terms, so the weight means the same at every
    // level). Automatic by default (`color_weight = auto` in a settings file): on each level, once
    // the depth terms have converged, the ratio of their robust variance to the colour terms' (each
    // term counts by the inverse of its noise). The balance then follows the recording: a scene's
    // contrast and a camera's exposure scale the colour residuals, a sensor's depth noise the depth
    // ones, and neither moves it. A number fixes the weight instead (color_weight_auto false;
    // m^2 per squared intensity unit: 1e-3 makes an intensity error of 0.03 count like 1 mm).
    bool color_weight_auto = true;
    float color_weight = 1e-3f;  // when color_weight_auto is false
    // rgbd: what the colour term aligns a frame's intensities to. The map's fused colours (frame to
    // model, the default) hold still while the estimate drifts, as the depth terms' model does; the
    // previous frame's (frame to frame) follows the drift, and needs no colour voxels or steady
    // exposure. Voxels without colour always fall back to the previous frame.
    bool color_from_map = true;
    // rgbd: the far field (FarFieldKeyframes). The map holds no depth beyond its range (SceneParams::
    // view_frustum_max_m), but a room's far walls pin the camera's rotation through their texture:
    // every far_field_spacing_m of camera motion (or far_field_spacing_deg of turn) a well tracked
    // frame's far depths, with its colours, become a keyframe, and the last far_field_keyframes
    // keyframes' points join the photometric terms (with a colour term's weight each). A keyframe
    // keeps the far_field_point_share of its points where its image is most textured. A camera that
    // circles a near object cannot tell a turn from a sideways step by the object's depth; the far
    // texture tells them apart. 0 keyframes: off.
    int far_field_keyframes = 3;
    float far_field_spacing_m = 0.05f;
    float far_field_spacing_deg = 10.f;
    float far_field_point_share = 1.f / 3.f;

    // Quality (see assessTrackingQuality): inlier ratio = inliers / valid pixels at full resolution;
    // condition = smallest / largest eigenvalue of the full-resolution normal matrix scaled to a unit
    // diagonal (free of units; near 0 when some motion is unconstrained).
    float good_inlier_ratio = 0.25f;   // below this: Poor
    float failed_inlier_ratio = 0.1f;  // below this: Failed
    float good_condition = 1e-3f;      // below this: Poor (one direction is weakly constrained)
    float failed_condition = 1e-6f;    // below this: Failed (a degenerate scene, e.g. one plane)
    // Below this share of the depth terms' weight along the least constrained translation: Poor (see
    // TrackingState::translation_constraint). Depth cannot tell how far the camera moved along that
    // direction, so the pose there is what noise and a few small structures made of it. The condition
    // above does not show it: it mixes rotation with translation, and a corridor's weak views
    // overlap real views that track well. The share separates them: real views that track well stay
    // several times above this threshold, views of a corridor's walls alone far below it.
    float poor_translation_constraint = 0.02f;
    float poor_residual_m = 0.01f;  // RMS point-to-plane residual above this: Poor
    // Colour tracker: an RMS intensity error above this means the images are not aligned (Failed);
    // aligned real frames stay well below it, unaligned ones well above.
    float failed_color_residual = 0.1f;
    int min_inliers = 100;  // fewer full-resolution inliers: Failed
    // A frame-to-frame motion beyond these is not believed (Failed): hand-held cameras at 30 Hz move far less.
    float max_motion_m = 0.3f;
    float max_motion_deg = 30.f;
};

// Throws ConfigError naming the setting when one is out of range.
void validateTrackerSettings(const TrackerSettings& settings);

// A key of the settings file that sets one field: the field, its range and what it means. The file's
// parser, the checks and `voxfuse --tracker-keys` are made from these rows; a field is added with its
// row. The keys of a list per level (levels, iterations, max_distance_m, pixel_step), tracker and
// color_weight (auto or a number) have parsers of their own (trackerSettingKeys lists them all).
using TrackerField = std::variant<float TrackerSettings::*, int TrackerSettings::*, bool TrackerSettings::*,
                                  RobustKernel TrackerSettings::*>;
struct TrackerSettingRow {
    const char* key;
    TrackerField field;
    double min = 0.0, max = 0.0;  // numbers: accepted range; max may be infinity
    bool min_open = false, max_open = false;
    const char* help = "";
};
const std::vector<TrackerSettingRow>& trackerSettingRows();
// Every key with its default and help, one per line, as `voxfuse --tracker-keys` prints them.
std::string trackerSettingKeys();

// Reads "key = value" lines ('#' starts a comment, blank lines are skipped) over the defaults:
//   tracker = icp | color | ren | rgbd
//   levels = rbb                    one letter per level, coarse to fine: r rotation, t translation, b both
//   iterations = 10 10 10           per level, coarse to fine (one value: every level)
//   max_distance_m = 0.1 0.05 0.02  per level, coarse to fine (one value: every level)
//   pixel_step = 1 1 1              per level, coarse to fine (one value: every level)
//   color_weight = auto             or a number
//   and one line per row of trackerSettingRows(); booleans are true/false/on/off/1/0, kernels none/huber/tukey.
// Throws IoError when the file cannot be read and ParseError(file, line, reason) for an unknown key,
// a malformed line, a bad value or a per-level list whose length does not match `levels`.
TrackerSettings parseTrackerSettingsFile(const std::string& path);
// The same for text already in memory; `name` stands for the file in error messages.
TrackerSettings parseTrackerSettings(const std::string& text, const std::string& name);

// What a front-end (the CLI, the Python API) lets a user change, applied in this order: the defaults,
// then the settings file, then the single values; all read by the parser above, so every value is
// checked the same way. Empty fields change nothing.
struct TrackerOverrides {
    std::string settings_file;                  // "key = value" lines as above
    std::string kind;                           // icp | color | ren | rgbd
    std::string levels;                         // e.g. "rbb"
    std::vector<int> iterations;                // per level, coarse to fine
    std::vector<float> max_distance_m;          // per level, coarse to fine
    std::string origin = "the given settings";  // where the single values come from, for error messages
};
TrackerSettings trackerSettingsWith(const TrackerOverrides& overrides);

}  // namespace voxfuse
