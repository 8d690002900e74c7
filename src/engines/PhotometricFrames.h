#pragma once
// The colour side of a tracker's state (host side, shared by the color and rgbd trackers): the
// current frame's intensity pyramid with gradients, and the previous frame's intensity and pose,
// which colour the model points (see ColorTracker.h for why the previous frame).

#include <vector>

#include "voxfuse/engines/ColorTracker.h"

namespace voxfuse {

class PhotometricFrames {
public:
    explicit PhotometricFrames(ColorTrackerKernels& kernels) : kernels_(kernels) {}

    // Builds the pyramid of the view's colour image (level 0 = full resolution). False when the view
    // has no colour image (or the calibration no colour camera).
    bool prepare(const View& view, int level_count);
    // Colours the model points (every `step`-th pixel of the depth camera's resolution, so that a
    // coarser model raycast gives the same points) with the map's colours where the model carries
    // them (RenderState::intensity: frame to model), else with the previous frame (frame to frame).
    // False when it has neither. After prepare().
    bool colorModel(const RenderState& model, int step);
    // The prepared frame becomes the previous one, its depth camera at T_world_camera. Not kept when
    // the map coloured this frame's model: it colours the next one too (the model's colours come with
    // the voxel type and tracker settings), and the frame would hold its image for nothing.
    void rememberCurrent(const Mat4f& T_world_camera);
    void forget() { has_previous_ = false; }
    bool holdsPreviousFrame() const { return has_previous_; }

    int levelCount() const { return int(levels_.size()); }
    const ColorFrameLevel& level(int i) const { return levels_[std::size_t(i)]; }
    const Image<ColorPoint>& points() const { return points_; }
    // What every point of an iteration at pyramid level i shares, for the depth-camera pose estimate.
    ColorTermParams termParams(int i, const Mat4f& T_world_camera) const;

private:
    ColorTrackerKernels& kernels_;
    std::vector<ColorFrameLevel> levels_;
    Image<ColorPoint> points_;
    Mat4f T_rgb_depth_ = Mat4f::identity();
    int depth_width_ = 0;  // of the depth camera, from prepare()
    bool has_current_ = false;
    bool colored_from_map_ = false;  // by the last colorModel() since prepare()

    Image<float> previous_;  // full-resolution intensity of the previous frame
    Intrinsics previous_rgb_;
    Mat4f previous_T_rgb_world_ = Mat4f::identity();
    bool has_previous_ = false;
};

}  // namespace voxfuse
