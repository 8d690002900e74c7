// Host side of the colour tracker: Levenberg-Marquardt on SE(3), coarse to fine over the intensity
// pyramid. The per-point sums run in the device layer (ColorTrackerKernels).

#include "voxfuse/engines/ColorTracker.h"

#include <algorithm>
#include <cmath>

#include "PhotometricFrames.h"
#include "PoseUpdate.h"
#include "voxfuse/core/Timer.h"
#include "voxfuse/engines/LowLevelEngine.h"

namespace voxfuse {
namespace {

constexpr double kInitialLambda = 1e-3;  // LM damping, relative to the diagonal
constexpr double kMaxLambda = 1e6;       // give up on a level when steps keep failing

double meanCost(const NormalEquations<double>& eq) { return eq.count > 0 ? eq.weighted_cost / eq.count : 0.0; }

class ColorTracker final : public Tracker {
public:
    ColorTracker(const TrackerSettings& settings, Device device)
        : settings_(settings),
          low_level_(makeLowLevelEngine(device)),
          kernels_(makeColorTrackerKernels(device)),
          frames_(*kernels_) {}

    void track(TrackingState& state, const View& view, const RenderState& model) override {
        const Timer total;
        stats_ = TrackerStats();
        const Timer prepare;
        const bool has_color = frames_.prepare(view, int(settings_.levels.size()));
        const bool has_model = hasTrackableSurface(model, *low_level_);
        const bool colored = has_color && has_model && frames_.colorModel(model, settings_.color_point_step);
        stats_.prepare_ms = prepare.elapsedMs();

        if (colored) {
            estimatePose(state);
        } else {
            // No map yet (the first frame, or nothing fused so far): this frame's pose defines it. No
            // colour, or a map that vanished: Failed. A map but no earlier colour frame to colour it:
            // the pose is kept, unverified (Poor).
            state.quality = !has_model && !seen_model_ ? TrackingQuality::Good
                            : !has_color || !has_model ? TrackingQuality::Failed
                                                       : TrackingQuality::Poor;
            state.inlier_ratio = state.quality == TrackingQuality::Good ? 1.f : 0.f;
            state.residual_m = 0.f;
            state.condition = state.quality == TrackingQuality::Good ? 1.f : 0.f;
        }
        seen_model_ = seen_model_ || has_model;
        if (state.quality == TrackingQuality::Failed)
            frames_.forget();
        else
            frames_.rememberCurrent(state.T_world_camera);
        stats_.total_ms = total.elapsedMs();
    }

    void reset() override {
        seen_model_ = false;
        forgetLastPose();
    }
    void forgetLastPose() override { frames_.forget(); }
    const TrackerStats& lastStats() const override { return stats_; }
    const TrackerSettings& settings() const override { return settings_; }
    TrackerInputs inputs() const override { return TrackerInputs{}; }  // it aligns frame to frame

private:
    NormalEquations<double> evaluate(int pyramid_level, const Eigen::Matrix4d& T) {
        return kernels_->accumulate(frames_.points(), frames_.level(pyramid_level),
                                    frames_.termParams(pyramid_level, pose::toMat4f(T)), settings_.color_kernel,
                                    settings_.color_kernel_scale);
    }

    void estimatePose(TrackingState& state) {
        const Eigen::Matrix4d T_start = pose::toEigenD(state.T_world_camera);
        Eigen::Matrix4d T = T_start;
        NormalEquations<double> finest = NormalEquations<double>::zero();
        for (int li = 0; li < int(settings_.levels.size()); ++li) finest = refineOnLevel(li, T);

        const int colored = kernels_->countColoredPoints(frames_.points());
        TrackingMeasures m;
        m.inliers = finest.count;
        m.inlier_ratio = colored > 0 ? float(finest.count) / float(colored) : 0.f;
        m.condition = pose::conditionRatio(finest);
        m.color_rms = finest.count > 0 ? float(std::sqrt(finest.squared_sum / finest.count)) : 0.f;
        pose::motionBetween(T_start, T, m.motion_m, m.motion_deg);
        state.quality = T.allFinite() ? assessTrackingQuality(settings_, m) : TrackingQuality::Failed;
        state.inlier_ratio = m.inlier_ratio;
        state.residual_m = m.color_rms;
        state.condition = m.condition;
        if (state.quality != TrackingQuality::Failed) state.T_world_camera = pose::toMat4f(T);
    }

    // Levenberg-Marquardt on settings level `li` (coarse to fine), updating T. Returns the system at
    // the final T.
    NormalEquations<double> refineOnLevel(int li, Eigen::Matrix4d& T) {
        const TrackerLevel& ls = settings_.levels[std::size_t(li)];
        const int pi = int(settings_.levels.size()) - 1 - li;
        TrackerLevelStats stats;
        stats.width = frames_.level(pi).intensity.width();
        stats.height = frames_.level(pi).intensity.height();
        const Timer level_time;
        NormalEquations<double> eq = evaluate(pi, T);
        double lambda = kInitialLambda;
        for (int it = 0; it < ls.max_iterations && eq.count >= 6; ++it) {
            stats.iterations = it + 1;
            pose::Vector6d x;
            if (!pose::solveUpdate(eq, ls.motion, lambda, x)) break;
            const Eigen::Matrix4d T_new = pose::applyUpdate(T, x);
            const NormalEquations<double> eq_new = evaluate(pi, T_new);
            // Mean cost: a step that pushes points out of the image must not look like progress.
            if (eq_new.count >= 6 && meanCost(eq_new) < meanCost(eq)) {
                T = T_new;
                eq = eq_new;
                lambda = std::max(lambda * 0.1, 1e-7);
                if (x.head<3>().norm() < settings_.min_rotation_step_rad &&
                    x.tail<3>().norm() < settings_.min_translation_step_m)
                    break;
            } else {
                lambda *= 10.0;
                if (lambda > kMaxLambda) break;
            }
        }
        stats.ms = level_time.elapsedMs();
        stats.inliers = eq.count;
        stats.rms_residual = eq.count > 0 ? float(std::sqrt(eq.squared_sum / eq.count)) : 0.f;
        stats_.levels.push_back(stats);
        return eq;
    }

    TrackerSettings settings_;
    std::unique_ptr<LowLevelEngine> low_level_;  // for the model's point count
    std::unique_ptr<ColorTrackerKernels> kernels_;
    PhotometricFrames frames_;
    bool seen_model_ = false;  // a map existed: from now on an empty model means lost tracking
    TrackerStats stats_;
};

}  // namespace

std::unique_ptr<Tracker> makeColorTracker(const TrackerSettings& settings, Device device) {
    return std::make_unique<ColorTracker>(settings, device);
}

}  // namespace voxfuse
