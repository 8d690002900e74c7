// Host side of the icp, ren and rgbd trackers: the frame pyramid, Gauss-Newton on SE(3) coarse to
// fine, and the quality of the result. The per-pixel sums run in the device layer (DepthTrackerKernels).

#include "voxfuse/engines/DepthTracker.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "FarFieldKeyframes.h"
#include "PhotometricFrames.h"
#include "MotionPredictor.h"
#include "PoseUpdate.h"
#include "voxfuse/core/Timer.h"
#include "voxfuse/engines/LowLevelEngine.h"

namespace voxfuse {
namespace {

// Pyramid downsampling averages only depths within this of each other (no surfaces across edges).
constexpr float kPyramidMaxDepthDiffM = 0.05f;
// rgbd's automatic colour weight takes the residuals' noise as at least this: a tenth of a millimetre
// of depth, one grey level of an 8-bit intensity.
constexpr double kDepthNoiseFloorM = 1e-4;
constexpr double kIntensityNoiseFloor = 1.0 / 255.0;

class DepthTracker final : public Tracker {
public:
    DepthTracker(const TrackerSettings& settings, Device device)
        : settings_(settings), low_level_(makeLowLevelEngine(device)), kernels_(makeDepthTrackerKernels(device)) {
        if (settings.kind == TrackerKind::Rgbd) {
            color_kernels_ = makeColorTrackerKernels(device);
            photometric_ = std::make_unique<PhotometricFrames>(*color_kernels_);
            if (settings.far_field_keyframes > 0)
                far_field_ = std::make_unique<FarFieldKeyframes>(*color_kernels_, settings, device);
        }
        pyramid_.resize(settings.levels.size());
        min_normal_cos_ = settings.max_normal_angle_deg >= 180.f
                              ? -2.f
                              : std::cos(settings.max_normal_angle_deg * float(EIGEN_PI) / 180.f);
    }

    void track(TrackingState& state, const View& view, const RenderState& model) override {
        const Timer total;
        stats_ = TrackerStats();
        const Timer prepare;
        const bool frame_ok = preparePyramid(view);
        const bool model_ok = hasTrackableSurface(model, *low_level_);
        const bool color_prepared = photometric_ && photometric_->prepare(view, levelCount());
        const bool color_ok = color_prepared && model_ok && photometric_->colorModel(model, settings_.color_point_step);
        stats_.prepare_ms = prepare.elapsedMs();

        if (frame_ok && !model_ok && !seen_model_) {
            // No map yet (the first frame, or nothing fused so far): this frame's pose defines it.
            state.quality = TrackingQuality::Good;
            state.inlier_ratio = 1.f;
            state.residual_m = 0.f;
            state.condition = 1.f;
            state.translation_constraint = 1.f / 3.f;
        } else if (!model_ok || !frame_ok) {
            reportFailed(state);
        } else {
            estimatePose(state, view, model, color_ok);
        }
        seen_model_ = seen_model_ || model_ok;
        if (state.quality == TrackingQuality::Failed)
            motion_.forget();
        else
            motion_.record(state.T_world_camera, view.clock());
        if (far_field_) {
            // Before rememberCurrent, which hands the colour pyramid's finest level on.
            if (state.quality == TrackingQuality::Failed)
                far_field_->forget();
            else if (state.quality == TrackingQuality::Good && color_prepared)
                far_field_->offer(view, state.T_world_camera, photometric_->level(0),
                                  photometric_->termParams(0, state.T_world_camera).T_rgb_depth);
        }
        if (photometric_) {
            if (state.quality == TrackingQuality::Failed)
                photometric_->forget();  // its pose is unknown: it must not colour the next model
            else
                photometric_->rememberCurrent(state.T_world_camera);
        }
        stats_.total_ms = total.elapsedMs();
    }

    void reset() override {
        seen_model_ = false;
        forgetLastPose();
    }
    void forgetLastPose() override {
        motion_.forget();
        if (photometric_) photometric_->forget();
        if (far_field_) far_field_->forget();
    }
    const TrackerStats& lastStats() const override { return stats_; }
    const TrackerSettings& settings() const override { return settings_; }
    // rgbd's colour term aligns to the map's colours, and its far-field keyframes use the far depths.
    TrackerInputs inputs() const override {
        const bool rgbd = settings_.kind == TrackerKind::Rgbd;
        return TrackerInputs{rgbd && settings_.far_field_keyframes > 0, rgbd && settings_.color_from_map};
    }

private:
    int levelCount() const { return int(settings_.levels.size()); }

    // Levels of the current frame: index 0 is full resolution (settings_.levels runs the other way).
    bool preparePyramid(const View& view) {
        valid_pixels_ = 0;
        if (view.depth.empty() || !view.calib.depth.valid() || view.depth.size() != view.calib.depth.size())
            return false;
        for (int i = 0; i < levelCount(); ++i) {
            DepthFrameLevel& level = pyramid_[std::size_t(i)];
            level.intrinsics = view.calib.depth.downsampled(1 << i);
            if (i > 0) {
                low_level_->downsampleDepth(pyramid_[std::size_t(i - 1)].depth, level.depth, kPyramidMaxDepthDiffM);
            } else {
                if (settings_.bilateral_filter)
                    low_level_->bilateralFilterDepth(view.depth, level.depth, BilateralFilterParams{});
                else
                    low_level_->copyDepth(view.depth, level.depth);
                // After the filter, which mixes only depths close to each other; the coarser levels inherit it.
                if (settings_.max_tracking_depth_m > 0.f)
                    low_level_->dropDepthBeyond(level.depth, settings_.max_tracking_depth_m);
            }
            // Only the points and normals the level's terms read (a level taking every second pixel reads a quarter).
            low_level_->computeGridPointsAndNormals(
                level.depth, level.intrinsics, settings_.max_normal_edge_m * float(1 << i),
                settings_.levels[std::size_t(levelCount() - 1 - i)].pixel_step, level.vertices, level.normals);
        }
        // Counted on the pixels the finest level takes terms from, as its inliers are.
        valid_pixels_ = low_level_->countValidDepth(pyramid_[0].depth, settings_.levels.back().pixel_step);
        return valid_pixels_ > 0;
    }

    void estimatePose(TrackingState& state, const View& view, const RenderState& model, bool use_color) {
        const Eigen::Matrix4d T_start = pose::toEigenD(state.T_world_camera);
        Eigen::Matrix4d T = settings_.predict_motion ? motion_.predict(state.T_world_camera, view.clock()) : T_start;
        NormalEquations<double> finest = NormalEquations<double>::zero();
        bool robust = false;  // ren and rgbd: least squares has handed over to the kernel
        // Which far-field points the frame sees, judged once at the predicted pose.
        const Image<ColorPoint>* far_points =
            use_color && far_field_ ? far_field_->unhiddenPoints(view, pose::toMat4f(T)) : nullptr;
        for (int li = 0; li < levelCount(); ++li) finest = refineOnLevel(li, model, use_color, far_points, T, robust);

        // Quality from the last full-resolution system (evaluated just before the last, small, update).
        TrackingMeasures m;
        m.inliers = finest.count;
        m.inlier_ratio = float(finest.count) / float(valid_pixels_);
        m.condition = pose::conditionRatio(finest);
        m.translation_constraint = float(pose::translationConstraint(finest).share(0));
        m.depth_rms_m = finest.count > 0 ? float(std::sqrt(finest.squared_sum / finest.count)) : 0.f;
        pose::motionBetween(T_start, T, m.motion_m, m.motion_deg);
        state.quality = T.allFinite() ? assessTrackingQuality(settings_, m) : TrackingQuality::Failed;
        state.inlier_ratio = m.inlier_ratio;
        state.residual_m = m.depth_rms_m;
        state.condition = m.condition;
        state.translation_constraint = m.translation_constraint;
        if (state.quality != TrackingQuality::Failed) state.T_world_camera = pose::toMat4f(T);
    }

    // Gauss-Newton on settings level `li` (coarse to fine), updating T and `robust` (see below). Returns
    // the depth system of the last iteration.
    NormalEquations<double> refineOnLevel(int li, const RenderState& model, bool use_color,
                                          const Image<ColorPoint>* far_points, Eigen::Matrix4d& T, bool& robust) {
        const TrackerLevel& ls = settings_.levels[std::size_t(li)];
        const int pi = levelCount() - 1 - li;
        const DepthFrameLevel& level = pyramid_[std::size_t(pi)];
        // ren: least squares first converges without the kernel (within the level's outlier distance
        // it captures motions far beyond the kernel's scale), then iterates on with it; the finer levels
        // start from that pose and use the kernel throughout. Every level thus ends on the same robust
        // cost. Should the coarsest level run out of iterations before least squares has converged (a
        // large motion whose path first slides far along a weak direction), the next level goes on
        // with least squares: the kernel's 1 cm basin cannot catch a pose centimetres off, and the
        // hand-over must not depend on how the path's rounding happens to fall on a device.
        // rgbd adds colour to ren's depth terms: without the kernel its depth terms would be icp's, and
        // so would its accuracy, whatever the colour weight.
        const bool kernel_on_depth = settings_.kind == TrackerKind::Ren || settings_.kind == TrackerKind::Rgbd;
        const RobustKernel final_kernel = kernel_on_depth ? settings_.robust_kernel : RobustKernel::None;
        if (final_kernel == RobustKernel::None) robust = true;
        const Mat4f T_model_world = rigidInverse(model.T_world_camera);
        TrackerLevelStats stats;
        stats.width = level.depth.width();
        stats.height = level.depth.height();
        const Timer level_time;
        NormalEquations<double> depth_eq = NormalEquations<double>::zero();
        // rgbd: photometric terms have a basin of a few pixels, so they join only once depth alone has
        // converged on this level, and then refine together with it until both agree. While they do,
        // the depth terms are the quadratic Gauss-Newton model of their cost about the pose where they
        // converged (colour moves the pose a millimetre or two, too little to change which model
        // points they meet or their weights): colour iterations cost the colour terms alone, and give
        // the poses that evaluating the depth terms at every colour iteration gives.
        bool with_color = false;
        double color_weight = -1.0;  // of a colour term against a depth term on this level; < 0: not yet known
        pose::StepExtrapolation extrapolation;
        NormalEquations<double> converged_depth = NormalEquations<double>::zero();
        pose::Vector6d moved_since = pose::Vector6d::Zero();  // the steps taken since the depth terms were evaluated
        // Steps are stretched only where the depth terms pin every translation (the frame would not be
        // poor): along a direction they barely constrain (a corridor's length) successive steps are
        // slides, not a converging series, and stretching them sends the pose astray along it.
        // Decided when the depth terms are evaluated; the colour phase keeps their J^T W J.
        bool depth_pins_translation = false;
        for (int it = 0; it < ls.max_iterations; ++it) {
            const Mat4f T_f = pose::toMat4f(T);
            const DepthTermParams params{T_f, T_model_world, model.intrinsics, ls.max_distance_m, min_normal_cos_};
            if (with_color) {
                depth_eq = depthSystemMovedBy(converged_depth, moved_since);
            } else {
                depth_eq = kernels_->accumulate(level, model, params, robust ? final_kernel : RobustKernel::None,
                                                settings_.robust_scale_m);
                converged_depth = depth_eq;
                moved_since.setZero();
                depth_pins_translation =
                    settings_.extrapolate_steps &&
                    pose::translationConstraint(depth_eq).share(0) >= double(settings_.poor_translation_constraint);
            }
            stats.iterations = it + 1;
            NormalEquations<double> system = depth_eq;
            if (with_color) {
                const NormalEquations<double> color_eq = color_kernels_->accumulate(
                    photometric_->points(), photometric_->level(pi), photometric_->termParams(pi, T_f),
                    settings_.color_kernel, settings_.color_kernel_scale);
                if (color_eq.count > 0 && depth_eq.count > 0) {
                    // Fixed for the level at its first colour iteration with terms: a weight that moved
                    // with every step's residuals would make a different cost at each iteration.
                    if (color_weight < 0.0)
                        color_weight =
                            settings_.color_weight_auto
                                ? pose::inverseVarianceWeight(depth_eq, kDepthNoiseFloorM * kDepthNoiseFloorM, color_eq,
                                                              kIntensityNoiseFloor * kIntensityNoiseFloor)
                                : double(settings_.color_weight);
                    // Per term: the colour points are fixed by the model while the depth pixels shrink 4x
                    // per level, so the colour sum is scaled to the depth term count.
                    const double per_color_term = color_weight * depth_eq.count / color_eq.count;
                    system.add(color_eq, per_color_term);
                    // The far field's terms count as the model's colour terms do, one for one: they
                    // add constraints, not another colour term to share the weight with.
                    if (far_points)
                        system.add(color_kernels_->accumulate(*far_points, photometric_->level(pi),
                                                              photometric_->termParams(pi, T_f), settings_.color_kernel,
                                                              settings_.color_kernel_scale),
                                   per_color_term);
                }
            }
            pose::Vector6d x;
            if (system.count < 6 || !pose::solveUpdate(system, ls.motion, 0.0, x)) break;
            if (!depth_pins_translation) extrapolation.restart();
            const pose::Vector6d taken = depth_pins_translation ? extrapolation.stretch(x) : x;
            T = pose::applyUpdate(T, taken);
            moved_since += taken;
            // Least squares only has to reach the kernel's basin: it hands over at ten times the final step.
            // A level's pixels are 2^pi times the finest's: it stops at steps that much larger (the finer
            // levels refine what it leaves). The test takes the Gauss-Newton step, not the stretched one.
            const double step_scale = (robust ? 1.0 : 10.0) * double(1 << pi);
            if (x.head<3>().norm() < step_scale * settings_.min_rotation_step_rad &&
                x.tail<3>().norm() < step_scale * settings_.min_translation_step_m) {
                extrapolation.restart();  // the kernel or colour joins: another cost
                if (!robust) {
                    robust = true;
                    continue;
                }
                if (with_color || !use_color) break;
                with_color = true;
            }
        }
        stats.ms = level_time.elapsedMs();
        stats.inliers = depth_eq.count;
        stats.rms_residual = depth_eq.count > 0 ? float(std::sqrt(depth_eq.squared_sum / depth_eq.count)) : 0.f;
        stats_.levels.push_back(stats);
        return depth_eq;
    }

    // The depth system of `at` evaluated after the pose moved by `moved` (small): the Gauss-Newton
    // model keeps J^T W J and moves the gradient to J^T W (r + J moved).
    static NormalEquations<double> depthSystemMovedBy(const NormalEquations<double>& at, const pose::Vector6d& moved) {
        NormalEquations<double> eq = at;
        const pose::Vector6d shift = pose::fullMatrix(at) * moved;
        for (int k = 0; k < 6; ++k) eq.gradient[k] += shift(k);
        return eq;
    }

    static void reportFailed(TrackingState& state) {
        state.quality = TrackingQuality::Failed;
        state.inlier_ratio = 0.f;
        state.residual_m = 0.f;
        state.condition = 0.f;
        state.translation_constraint = 0.f;
    }

    TrackerSettings settings_;
    std::unique_ptr<LowLevelEngine> low_level_;
    std::unique_ptr<DepthTrackerKernels> kernels_;
    std::unique_ptr<ColorTrackerKernels> color_kernels_;  // rgbd only
    std::unique_ptr<PhotometricFrames> photometric_;      // rgbd only
    std::unique_ptr<FarFieldKeyframes> far_field_;        // rgbd with far_field_keyframes > 0
    std::vector<DepthFrameLevel> pyramid_;
    int valid_pixels_ = 0;
    float min_normal_cos_ = -2.f;
    bool seen_model_ = false;  // a map existed: from now on an empty model means lost tracking
    MotionPredictor motion_;
    TrackerStats stats_;
};

}  // namespace

std::unique_ptr<Tracker> makeDepthTracker(const TrackerSettings& settings, Device device) {
    return std::make_unique<DepthTracker>(settings, device);
}

}  // namespace voxfuse
