#include "voxfuse/engines/Relocaliser.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "voxfuse/core/Error.h"
#include "voxfuse/shared/ColorTrackerTerms.h"  // intensityFromRgb

namespace voxfuse {

DepthAgreement compareDepth(const Image<float>& frame_depth_m, const Image<float>& model_depth_m, float tolerance_m) {
    if (frame_depth_m.size() != model_depth_m.size())
        throw ConfigError("compareDepth: the frame and the model differ in size");
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

namespace {

// Sums of one cell's intensities (0-255), their squares and products.
struct CorrelationSums {
    double n = 0, f = 0, m = 0, ff = 0, mm = 0, fm = 0;
    void add(double fi, double mi) {
        n += 1;
        f += fi;
        m += mi;
        ff += fi * fi;
        mm += mi * mi;
        fm += fi * mi;
    }
};

// The frame's intensities (0-255) summed over boxes in constant time: a summed-area table.
class BoxIntensity {
public:
    explicit BoxIntensity(const Image<Vec4u8>& rgb) : width_(rgb.width()), height_(rgb.height()) {
        sums_.assign(std::size_t(width_ + 1) * std::size_t(height_ + 1), 0.0);
        for (int v = 0; v < height_; ++v) {
            double row = 0.0;
            for (int u = 0; u < width_; ++u) {
                row += 255.0 * double(intensityFromRgb(rgb.at(u, v)));
                at(u + 1, v + 1) = at(u + 1, v) + row;
            }
        }
    }
    // The mean over the pixels whose centres lie within `half` of (x, y) on each axis, at least the
    // nearest one; -1 when (x, y) lies outside the image.
    double mean(float x, float y, float half) const {
        if (!(x >= -0.5f && y >= -0.5f && x < float(width_) - 0.5f && y < float(height_) - 0.5f)) return -1.0;
        half = std::min(half, float(width_ + height_));  // no wider than the image, whatever the depth
        int u0 = std::max(0, int(std::ceil(x - half))), u1 = std::min(width_ - 1, int(std::floor(x + half)));
        int v0 = std::max(0, int(std::ceil(y - half))), v1 = std::min(height_ - 1, int(std::floor(y + half)));
        if (u0 > u1 || v0 > v1) {  // narrower than a pixel: the nearest
            u0 = u1 = std::min(width_ - 1, int(x + 0.5f));
            v0 = v1 = std::min(height_ - 1, int(y + 0.5f));
        }
        const double sum = at(u1 + 1, v1 + 1) - at(u0, v1 + 1) - at(u1 + 1, v0) + at(u0, v0);
        return sum / (double(u1 - u0 + 1) * double(v1 - v0 + 1));
    }

private:
    double& at(int u, int v) { return sums_[std::size_t(u) + std::size_t(v) * std::size_t(width_ + 1)]; }
    double at(int u, int v) const { return sums_[std::size_t(u) + std::size_t(v) * std::size_t(width_ + 1)]; }
    int width_, height_;
    std::vector<double> sums_;
};

}  // namespace

ColorAgreement compareColor(const View& view, const Image<float>& model_depth_m, const Image<float>& model_intensity,
                            float tolerance_m, float voxel_size_m, int min_textured_cells) {
    ColorAgreement a;
    const Image<float>& frame_depth_m = view.depth;
    if (view.rgb.empty() || model_intensity.empty() || !view.calib.rgb.valid()) return a;
    if (frame_depth_m.size() != model_depth_m.size() || model_intensity.size() != model_depth_m.size())
        throw ConfigError(
            "compareColor: the frame's depth, the model's depth and the model's intensities differ in size");
    const Intrinsics& depth_camera = view.calib.depth;
    const Intrinsics rgb_camera = view.colorCamera();  // at the colour image's resolution
    const Mat4f T_rgb_depth = rigidInverse(view.calib.T_depth_rgb);
    const int width = frame_depth_m.width(), height = frame_depth_m.height();
    const int cell = std::max(kColorCellMinPixels, width / kColorCellsAcross);
    const int cells_x = (width + cell - 1) / cell, cells_y = (height + cell - 1) / cell;
    std::vector<CorrelationSums> cells(std::size_t(cells_x) * std::size_t(cells_y));
    const float* frame = frame_depth_m.host();
    const float* model = model_depth_m.host();
    const float* model_grey = model_intensity.host();
    const BoxIntensity frame_intensity(view.rgb);
    // Half the footprint, in colour pixels, of the model's colour at one metre.
    const float half_footprint_px_m =
        0.5f * kColorFootprintVoxels * voxel_size_m * 0.5f * (rgb_camera.fx + rgb_camera.fy);
    for (int v = 0; v < height; ++v)
        for (int u = 0; u < width; ++u) {
            const int i = u + v * width;
            if (!(frame[i] > 0.f) || !(model[i] > 0.f) || !(std::fabs(frame[i] - model[i]) < tolerance_m)) continue;
            const Vec3f p_rgb = transformPoint(T_rgb_depth, depth_camera.unproject(float(u), float(v), frame[i]));
            if (!(p_rgb.z > 0.f)) continue;
            // -1: voxels that never saw colour (fused from frames without it, or outside the colour
            // camera's view): nothing to compare.
            if (!(model_grey[i] >= 0.f)) continue;
            const Vec2f px = rgb_camera.project(p_rgb);
            const double f = frame_intensity.mean(px.x, px.y, half_footprint_px_m / p_rgb.z);
            if (f < 0.0) continue;
            cells[std::size_t(u / cell + (v / cell) * cells_x)].add(f, 255.0 * double(model_grey[i]));
        }
    // Each cell's correlation, weighed by its pixels; cells with few pixels, or plain on either side
    // (less than 3 grey levels of deviation: a wall, or sensor noise on one), have no say.
    constexpr double kMinVariance = 9.0;
    const double min_pixels = 0.25 * double(cell) * double(cell);
    double weighted = 0.0, pixels = 0.0;
    int textured = 0;
    for (const CorrelationSums& c : cells) {
        if (c.n < min_pixels) continue;
        const double var_f = c.ff / c.n - (c.f / c.n) * (c.f / c.n), var_m = c.mm / c.n - (c.m / c.n) * (c.m / c.n);
        if (!(var_f > kMinVariance) || !(var_m > kMinVariance)) continue;
        weighted += c.n * (c.fm / c.n - (c.f / c.n) * (c.m / c.n)) / std::sqrt(var_f * var_m);
        pixels += c.n;
        ++textured;
    }
    a.pixels = int(pixels);
    a.cells = textured;
    if (textured == 0 || textured < min_textured_cells) return a;
    a.compared = true;
    a.correlation = float(weighted / pixels);
    return a;
}

bool acceptRelocalisation(const RelocalisationSettings& s, const RelocalisationCheck& c) {
    // Every comparison is false for a NaN, so a NaN measure rejects.
    return c.refined.quality == TrackingQuality::Good && c.refined.inlier_ratio >= s.min_inlier_ratio &&
           c.refined.residual_m <= s.max_residual_m && c.depth.overlap >= s.min_overlap &&
           c.depth.agreement >= s.min_agreement && c.step_m <= s.max_refinement_step_m &&
           c.step_deg <= s.max_refinement_step_deg &&
           (!c.color.compared || c.color.correlation >= s.min_color_correlation);
}

bool withinReach(const RelocalisationSettings& s, const Mat4f& T_world_last, const Mat4f& T_world_candidate,
                 double elapsed_s) {
    if (!(s.max_speed_m_per_s > 0.f) || !(elapsed_s > 0.0)) return true;
    const Vec3f d = T_world_candidate.translation() - T_world_last.translation();
    return double(std::sqrt(dot(d, d))) <= double(s.max_speed_m_per_s) * elapsed_s;
}

Relocaliser::Relocaliser(const RelocalisationSettings& settings, Vec2i frame_size, Device device)
    : settings_(settings), frame_size_(frame_size), device_(device), database_(settings.max_keyframes) {
    if (settings.candidates < 1) throw ConfigError("relocalisation tries at least one keyframe per frame");
    if (!(settings.max_speed_m_per_s >= 0.f))
        throw ConfigError("the relocalisation speed limit is a speed in m/s, 0 for none");
    if (!(settings.keyframe_min_dissimilarity >= 0.f && settings.keyframe_min_dissimilarity <= 1.f))
        throw ConfigError("the keyframe dissimilarity threshold lies in [0, 1]");
    if (!(settings.min_color_correlation >= -1.f && settings.min_color_correlation <= 1.f))
        throw ConfigError("the relocalisation's least colour correlation lies in [-1, 1] (-1: no colour test)");
    FernEncoder check(settings.ferns, frame_size, false);  // ConfigError now rather than at the first frame
}

Relocaliser::~Relocaliser() = default;

FernCode Relocaliser::encode(const View& view) {
    if (!encoder_) {
        // Codes of the kind the adopted keyframes have, whatever this frame has (a view without colour
        // reads intensity 0): the saved keyframes stay comparable.
        const bool with_intensity = adopted_intensity_ >= 0 ? adopted_intensity_ == 1 : !view.rgb.empty();
        encoder_ = std::make_unique<FernEncoder>(settings_.ferns, frame_size_, with_intensity, device_);
        adopted_intensity_ = -1;
    }
    return encoder_->encode(view.depth, view.rgb);
}

MapKeyframes Relocaliser::savedKeyframes() const {
    MapKeyframes saved;
    saved.ferns = settings_.ferns;
    saved.frame_size = frame_size_;
    saved.with_intensity = encoder_ ? encoder_->withIntensity() : adopted_intensity_ == 1;
    saved.keyframes = database_.oldestFirst();
    return saved;
}

bool Relocaliser::adoptKeyframes(const MapKeyframes& saved) {
    const FernSettings &a = saved.ferns, &b = settings_.ferns;
    const bool alike = a.fern_count == b.fern_count && a.tests_per_fern == b.tests_per_fern &&
                       a.image_width == b.image_width && a.min_depth_m == b.min_depth_m &&
                       a.max_depth_m == b.max_depth_m && a.use_intensity == b.use_intensity && a.seed == b.seed &&
                       saved.frame_size == frame_size_ &&
                       (!encoder_ || encoder_->withIntensity() == saved.with_intensity);
    database_.clear();
    if (!alike || saved.keyframes.empty()) return false;
    database_.assign(saved.keyframes);
    if (!encoder_) adopted_intensity_ = saved.with_intensity ? 1 : 0;
    return true;
}

bool Relocaliser::looksLost(const TrackingState& tracked) const {
    if (recent_inlier_ratios_.size() < 3) return false;  // too few to know what is normal here
    std::vector<float> recent = recent_inlier_ratios_;
    std::nth_element(recent.begin(), recent.begin() + std::ptrdiff_t(recent.size() / 2), recent.end());
    return !(tracked.inlier_ratio >= settings_.lost_inlier_ratio_drop * recent[recent.size() / 2]);
}

void Relocaliser::rememberGoodFrame(const TrackingState& tracked) {
    recent_inlier_ratios_.push_back(tracked.inlier_ratio);
    if (int(recent_inlier_ratios_.size()) > settings_.recent_frames)
        recent_inlier_ratios_.erase(recent_inlier_ratios_.begin());
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
    adopted_intensity_ = -1;
    forgetRecentFrames();
}

}  // namespace voxfuse
