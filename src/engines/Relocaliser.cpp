#include "voxfuse/engines/Relocaliser.h"

#include <algorithm>
#include <cmath>

#include "voxfuse/core/Error.h"

namespace voxfuse {

DepthAgreement compareDepth(const Image<float>& frame_depth_m, const Image<float>& model_depth_m, float tolerance_m) {
    if (frame_depth_m.size() != model_depth_m.size()) throw ConfigError("compareDepth: the frame and the model differ in size");
    std::size_t valid = 0, both = 0, agree = 0;
    const float* frame = frame_depth_m.host();
    const float* model = model_depth_m.host();
    for (std::size_t i = 0; i < frame_depth_m.pixelCount(); ++i) {
        if (!(frame[i] > 0.f)) continue;
        ++valid;
        if (!(model[i] > 0.f)) continue;
        ++both;
        agree += std::fabs(frame[i] - model[i]) < tolerance_m;
    }
    DepthAgreement a;
    a.overlap = valid > 0 ? float(both) / float(valid) : 0.f;
    a.agreement = both > 0 ? float(agree) / float(both) : 0.f;
    return a;
}

bool acceptRelocalisation(const RelocalisationSettings& s, const RelocalisationCheck& c) {
    // Every comparison is false for a NaN, so a NaN measure rejects.
    return c.refined.quality == TrackingQuality::Good && c.refined.inlier_ratio >= s.min_inlier_ratio &&
           c.refined.residual_m <= s.max_residual_m && c.depth.overlap >= s.min_overlap && c.depth.agreement >= s.min_agreement &&
           c.step_m <= s.max_refinement_step_m && c.step_deg <= s.max_refinement_step_deg;
}

bool withinReach(const RelocalisationSettings& s, const Mat4f& T_world_last, const Mat4f& T_world_candidate, double elapsed_s) {
    if (!(s.max_speed_m_per_s > 0.f) || !(elapsed_s > 0.0)) return true;
    const Vec3f d = T_world_candidate.translation() - T_world_last.translation();
    return double(std::sqrt(dot(d, d))) <= double(s.max_speed_m_per_s) * elapsed_s;
}

Relocaliser::Relocaliser(const RelocalisationSettings& settings, Vec2i frame_size, Device device)
    : settings_(settings), frame_size_(frame_size), device_(device), database_(settings.max_keyframes) {
    if (settings.candidates < 1) throw ConfigError("relocalisation tries at least one keyframe per frame");
    if (!(settings.max_speed_m_per_s >= 0.f)) throw ConfigError("the relocalisation speed limit is a speed in m/s, 0 for none");
    if (!(settings.keyframe_min_dissimilarity >= 0.f && settings.keyframe_min_dissimilarity <= 1.f))
        throw ConfigError("the keyframe dissimilarity threshold lies in [0, 1]");
    FernEncoder check(settings.ferns, frame_size, false);  // ConfigError now rather than at the first frame
}

Relocaliser::~Relocaliser() = default;

FernCode Relocaliser::encode(const View& view) {
    if (!encoder_) encoder_ = std::make_unique<FernEncoder>(settings_.ferns, frame_size_, !view.rgb.empty(), device_);
    return encoder_->encode(view.depth, view.rgb);
}

bool Relocaliser::looksLost(const TrackingState& tracked) const {
    if (recent_inlier_ratios_.size() < 3) return false;  // too few to know what is normal here
    std::vector<float> recent = recent_inlier_ratios_;
    std::nth_element(recent.begin(), recent.begin() + std::ptrdiff_t(recent.size() / 2), recent.end());
    return !(tracked.inlier_ratio >= settings_.lost_inlier_ratio_drop * recent[recent.size() / 2]);
}

void Relocaliser::rememberGoodFrame(const TrackingState& tracked) {
    recent_inlier_ratios_.push_back(tracked.inlier_ratio);
    if (int(recent_inlier_ratios_.size()) > settings_.recent_frames) recent_inlier_ratios_.erase(recent_inlier_ratios_.begin());
}

bool Relocaliser::addKeyframe(const View& view, const Mat4f& T_world_camera) {
    return database_.addIfNovel(encode(view), T_world_camera, view.frame_index, settings_.keyframe_min_dissimilarity);
}

std::vector<KeyframeMatch> Relocaliser::lookUp(const View& view) {
    if (database_.size() == 0) return {};
    return database_.nearest(encode(view), settings_.candidates);
}

void Relocaliser::clear() {
    database_.clear();
    forgetRecentFrames();
}

}  // namespace voxfuse
