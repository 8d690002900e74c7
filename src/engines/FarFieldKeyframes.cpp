// rgbd's far field: keyframes of the depths beyond the map's range.

#include "FarFieldKeyframes.h"

#include <algorithm>

#include "PoseUpdate.h"

namespace voxfuse {

FarFieldKeyframes::FarFieldKeyframes(ColorTrackerKernels& kernels, const TrackerSettings& settings, Device device)
    : kernels_(kernels),
      keep_(settings.far_field_keyframes),
      point_step_(settings.color_point_step),
      spacing_m_(settings.far_field_spacing_m),
      spacing_deg_(settings.far_field_spacing_deg),
      point_share_(settings.far_field_point_share),
      device_(device) {}

const Image<ColorPoint>* FarFieldKeyframes::unhiddenPoints(const View& view, const Mat4f& T_world_camera) {
    if (all_.empty() || view.depth.empty()) return nullptr;
    kernels_.unhiddenFarFieldPoints(all_, view.depth, view.calib.depth, rigidInverse(T_world_camera), unhidden_);
    return &unhidden_;
}

void FarFieldKeyframes::offer(const View& view, const Mat4f& T_world_camera, const ColorFrameLevel& color,
                              const Mat4f& T_rgb_depth) {
    if (keep_ <= 0 || view.far_depth.empty() || view.far_depth.size() != view.calib.depth.size()) return;
    if (!keyframes_.empty()) {
        float moved_m = 0.f, turned_deg = 0.f;
        pose::motionBetween(pose::toEigenD(T_world_newest_), pose::toEigenD(T_world_camera), moved_m, turned_deg);
        if (moved_m < spacing_m_ && turned_deg < spacing_deg_) return;
    }
    kernels_.farFieldPoints(view.far_depth, view.calib.depth, point_step_, T_world_camera, color,
                            T_rgb_depth * rigidInverse(T_world_camera), candidates_, gradient_sq_);
    candidates_.memory().updateHost();
    gradient_sq_.memory().updateHost();
    const ColorPoint* points = static_cast<const Image<ColorPoint>&>(candidates_).host();
    const float* gradient_sq = static_cast<const Image<float>&>(gradient_sq_).host();

    // The best textured share: a point on a plain wall adds cost and no constraint.
    std::vector<float> coloured;
    for (std::size_t i = 0; i < candidates_.pixelCount(); ++i)
        if (points[i].intensity >= 0.f) coloured.push_back(gradient_sq[i]);
    std::vector<ColorPoint> kept;
    if (!coloured.empty()) {
        const std::size_t below =
            std::min(coloured.size() - 1, std::size_t(double(coloured.size()) * (1.0 - double(point_share_))));
        std::nth_element(coloured.begin(), coloured.begin() + std::ptrdiff_t(below), coloured.end());
        const float threshold = coloured[below];
        kept.reserve(coloured.size() - below);
        for (std::size_t i = 0; i < candidates_.pixelCount(); ++i)
            if (points[i].intensity >= 0.f && gradient_sq[i] >= threshold) kept.push_back(points[i]);
    }
    keyframes_.push_front(std::move(kept));
    while (int(keyframes_.size()) > keep_) keyframes_.pop_back();
    T_world_newest_ = T_world_camera;
    gatherPoints();
}

void FarFieldKeyframes::forget() {
    keyframes_.clear();
    all_ = Image<ColorPoint>();
}

void FarFieldKeyframes::gatherPoints() {
    std::size_t count = 0;
    for (const auto& k : keyframes_) count += k.size();
    if (count == 0) {
        all_ = Image<ColorPoint>();
        return;
    }
    all_.resize(Vec2i{int(count), 1});
    ColorPoint* out = all_.host();
    for (const auto& k : keyframes_) out = std::copy(k.begin(), k.end(), out);
    if (device_ == Device::CUDA) all_.memory().updateDevice();
}

}  // namespace voxfuse
