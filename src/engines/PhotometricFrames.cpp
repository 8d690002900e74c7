// Intensity pyramids and model colours for the colour and rgbd trackers.

#include "PhotometricFrames.h"

#include <algorithm>
#include <utility>

namespace voxfuse {

bool PhotometricFrames::prepare(const View& view, int level_count) {
    has_current_ = colored_from_map_ = false;
    depth_width_ = view.calib.depth.width;
    if (view.rgb.empty() || !view.calib.rgb.valid()) return false;
    const Intrinsics rgb = view.colorCamera();  // at the colour image's resolution
    levels_.resize(std::size_t(level_count));
    T_rgb_depth_ = rigidInverse(view.calib.T_depth_rgb);
    for (int i = 0; i < level_count; ++i) {
        ColorFrameLevel& level = levels_[std::size_t(i)];
        level.intrinsics = rgb.downsampled(1 << i);
        if (i == 0)
            kernels_.intensityFromRgb(view.rgb, level.intensity);
        else
            kernels_.downsampleIntensity(levels_[std::size_t(i - 1)].intensity, level.intensity);
        kernels_.sobelGradient(level.intensity, level.gradient);
    }
    has_current_ = true;
    return true;
}

bool PhotometricFrames::colorModel(const RenderState& model, int step) {
    const int model_step =
        depth_width_ > 0 ? std::max(1, (step * model.intrinsics.width + depth_width_ / 2) / depth_width_) : step;
    if (!model.intensity.empty()) {
        // The map's own colours, seen from where the model was raycast: each point projects onto its pixel.
        kernels_.colorModelPoints(model, model_step, model.intensity, model.intrinsics,
                                  rigidInverse(model.T_world_camera), points_);
        colored_from_map_ = true;
        return true;
    }
    if (!has_previous_) return false;
    kernels_.colorModelPoints(model, model_step, previous_, previous_rgb_, previous_T_rgb_world_, points_);
    return true;
}

void PhotometricFrames::rememberCurrent(const Mat4f& T_world_camera) {
    if (!has_current_ || colored_from_map_) {
        has_previous_ = false;
        previous_ = Image<float>();
        has_current_ = false;
        return;
    }
    // The next prepare() rebuilds level 0, so its buffer can simply change hands.
    std::swap(previous_, levels_[0].intensity);
    previous_rgb_ = levels_[0].intrinsics;
    previous_T_rgb_world_ = T_rgb_depth_ * rigidInverse(T_world_camera);
    has_previous_ = true;
    has_current_ = false;
}

ColorTermParams PhotometricFrames::termParams(int i, const Mat4f& T_world_camera) const {
    return ColorTermParams{rigidInverse(T_world_camera), T_rgb_depth_, levels_[std::size_t(i)].intrinsics};
}

}  // namespace voxfuse
