#pragma once
// rgbd's far field (host side): the depths beyond the map's range, with their colours, from the last
// few keyframes. The map holds nothing beyond SceneParams::view_frustum_max_m (far depth is a
// Kinect's noisiest, and fusing it at the map's voxel size would cost more memory than the near scene),
// so the model's photometric terms cannot see a room's far walls. Yet those are what tell a turn of
// the camera from a sideways step when the near scene is a single rounded object: a far point's image
// moves with the camera's rotation and hardly with its translation, so its depth need not be precise.
// Every few centimetres of camera motion the tracked frame's far depths become a keyframe's points in
// the world, coloured by that frame (the best textured share of them); the points of the last few
// keyframes then join the photometric terms of later frames, where nothing nearer hides them. They
// hold still while the estimate drifts, as the map does, until newer keyframes replace them.
// Per-point code: farFieldPoint, unhiddenFarFieldPoint (shared/ColorTrackerTerms.h), run by
// ColorTrackerKernels on either device.

#include <deque>
#include <vector>

#include "voxfuse/engines/ColorTracker.h"
#include "voxfuse/engines/TrackerSettings.h"

namespace voxfuse {

class FarFieldKeyframes {
public:
    FarFieldKeyframes(ColorTrackerKernels& kernels, const TrackerSettings& settings, Device device);

    // The kept keyframes' points as a frame (its depths within the map's range: view.depth) at
    // T_world_camera sees them: those outside its view or behind a surface it measured have no colour.
    // nullptr while no keyframe holds a point.
    const Image<ColorPoint>* unhiddenPoints(const View& view, const Mat4f& T_world_camera);
    // A well tracked frame at T_world_camera, its colour pyramid's finest level `color` (the colour
    // camera at T_rgb_depth from the depth camera): a new keyframe when the camera has moved
    // far_field_spacing_m or turned far_field_spacing_deg since the last one. Without far depths
    // (view.far_depth empty) nothing changes.
    void offer(const View& view, const Mat4f& T_world_camera, const ColorFrameLevel& color, const Mat4f& T_rgb_depth);
    // Drops every keyframe (tracking was lost: the last poses are not to be trusted).
    void forget();

    int keyframeCount() const { return int(keyframes_.size()); }
    int pointCount() const { return int(all_.pixelCount()); }

private:
    void gatherPoints();

    ColorTrackerKernels& kernels_;
    int keep_;
    int point_step_;  // a keyframe's points: every point_step_-th pixel in x and y, as the model's colour points
    float spacing_m_, spacing_deg_, point_share_;
    Device device_;
    std::deque<std::vector<ColorPoint>> keyframes_;  // newest first
    Mat4f T_world_newest_ = Mat4f::identity();
    Image<ColorPoint> all_;       // every keyframe's points, one row
    Image<ColorPoint> unhidden_;  // as the current frame sees them
    Image<ColorPoint> candidates_;
    Image<float> gradient_sq_;
};

}  // namespace voxfuse
