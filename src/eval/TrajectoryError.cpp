// ATE and RPE of an estimated trajectory against ground truth.

#include "voxfuse/eval/TrajectoryError.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

#include "../core/NearestInTime.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Eigen::Matrix4d toEigenD(const Mat4f& m) {
    Eigen::Matrix4d e;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) e(r, c) = m(r, c);
    return e;
}

std::vector<TimedPose> sortedByTime(std::vector<TimedPose> poses) {
    std::stable_sort(poses.begin(), poses.end(),
                     [](const TimedPose& a, const TimedPose& b) { return a.timestamp_s < b.timestamp_s; });
    return poses;
}

// Index of the pose nearest in time to t within max_dt, or -1. `poses` sorted by time.
int nearest(const std::vector<TimedPose>& poses, double t, double max_dt) {
    const TimedPose* p = nearestInTime(poses, t, max_dt, [](const TimedPose& pose) { return pose.timestamp_s; });
    return p ? int(p - poses.data()) : -1;
}

double rotationAngleRad(const Eigen::Matrix3d& R) { return std::acos(std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0)); }

void computeAte(const std::vector<TimedPose>& est, const std::vector<TimedPose>& gt, const TrajectoryErrorOptions& o,
                TrajectoryError& e) {
    std::vector<Eigen::Vector3d> src, dst;
    for (const TimedPose& p : est) {
        const int j = nearest(gt, p.timestamp_s + o.time_offset_s, o.max_time_difference_s);
        if (j < 0) continue;
        src.push_back(toEigenD(p.T_world_camera).topRightCorner<3, 1>());
        dst.push_back(toEigenD(gt[std::size_t(j)].T_world_camera).topRightCorner<3, 1>());
    }
    e.pairs = int(src.size());
    if (e.pairs < 3) {
        e.ate_rmse_m = e.ate_mean_m = e.ate_median_m = e.ate_max_m = kNaN;
        return;
    }
    Eigen::Matrix3Xd S(3, e.pairs), D(3, e.pairs);
    for (int i = 0; i < e.pairs; ++i) {
        S.col(i) = src[std::size_t(i)];
        D.col(i) = dst[std::size_t(i)];
    }
    const Eigen::Matrix4d T = Eigen::umeyama(S, D, false);
    std::vector<double> errors(std::size_t(e.pairs));
    double sum = 0.0, sum_sq = 0.0;
    for (int i = 0; i < e.pairs; ++i) {
        const double err = (T.topLeftCorner<3, 3>() * S.col(i) + T.topRightCorner<3, 1>() - D.col(i)).norm();
        errors[std::size_t(i)] = err;
        sum += err;
        sum_sq += err * err;
    }
    e.ate_rmse_m = std::sqrt(sum_sq / e.pairs);
    e.ate_mean_m = sum / e.pairs;
    e.ate_max_m = *std::max_element(errors.begin(), errors.end());
    std::sort(errors.begin(), errors.end());
    const std::size_t mid = errors.size() / 2;
    e.ate_median_m = errors.size() % 2 ? errors[mid] : 0.5 * (errors[mid - 1] + errors[mid]);
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) e.T_truth_estimate(r, c) = float(T(r, c));
}

void computeRpe(const std::vector<TimedPose>& est, const std::vector<TimedPose>& gt, const TrajectoryErrorOptions& o,
                TrajectoryError& e) {
    double sum_trans = 0.0, sum_rot = 0.0;
    for (std::size_t i = 0; i < est.size(); ++i) {
        const double t0 = est[i].timestamp_s;
        const int j = nearest(est, t0 + o.rpe_delta_s, o.max_time_difference_s);
        if (j < 0 || est[std::size_t(j)].timestamp_s <= t0) continue;
        const double t1 = est[std::size_t(j)].timestamp_s;
        const int g0 = nearest(gt, t0 + o.time_offset_s, o.max_time_difference_s),
                  g1 = nearest(gt, t1 + o.time_offset_s, o.max_time_difference_s);
        if (g0 < 0 || g1 < 0) continue;
        const Eigen::Matrix4d A =
            toEigenD(est[i].T_world_camera).inverse() * toEigenD(est[std::size_t(j)].T_world_camera);
        const Eigen::Matrix4d B =
            toEigenD(gt[std::size_t(g0)].T_world_camera).inverse() * toEigenD(gt[std::size_t(g1)].T_world_camera);
        const Eigen::Matrix4d E = A * B.inverse();
        const double dt = t1 - t0;
        const double trans = E.topRightCorner<3, 1>().norm() / dt;
        const double rot = rotationAngleRad(E.topLeftCorner<3, 3>()) * 180.0 / EIGEN_PI / dt;
        sum_trans += trans * trans;
        sum_rot += rot * rot;
        ++e.rpe_pairs;
    }
    e.rpe_trans_m_per_s = e.rpe_pairs > 0 ? std::sqrt(sum_trans / e.rpe_pairs) : kNaN;
    e.rpe_rot_deg_per_s = e.rpe_pairs > 0 ? std::sqrt(sum_rot / e.rpe_pairs) : kNaN;
}

// The offset search (TrajectoryError::best_time_offset_s).
void searchTimeOffset(const std::vector<TimedPose>& est, const std::vector<TimedPose>& gt,
                      const TrajectoryErrorOptions& o, TrajectoryError& e) {
    e.best_time_offset_s = e.ate_rmse_at_best_offset_m = kNaN;
    if (!(o.max_time_offset_s > 0.0) || e.pairs < 3) return;
    constexpr double kStep_s = 0.001;
    const int steps = int(std::floor(o.max_time_offset_s / kStep_s + 1e-9));
    // An offset may leave a few poses without a partner (ground truth has gaps), not more: dropping
    // the worst poses must not be what makes an offset best.
    const int min_pairs = std::max(3, e.pairs - std::max(1, e.pairs / 50));
    std::vector<double> rmse(std::size_t(2 * steps + 1), kNaN);  // per step, NaN where too few poses pair
    int best = -1;
    for (int k = 0; k <= 2 * steps; ++k) {
        TrajectoryErrorOptions shifted = o;
        shifted.time_offset_s = o.time_offset_s + (k - steps) * kStep_s;
        TrajectoryError at;
        computeAte(est, gt, shifted, at);
        if (at.pairs < min_pairs) continue;
        rmse[std::size_t(k)] = at.ate_rmse_m;
        if (best < 0 || at.ate_rmse_m < rmse[std::size_t(best)]) best = k;
    }
    if (best < 0) return;
    // The run of steps around the best that pair alike (equal RMSE): its middle.
    int first = best, last = best;
    while (first > 0 && rmse[std::size_t(first - 1)] == rmse[std::size_t(best)]) --first;
    while (last < 2 * steps && rmse[std::size_t(last + 1)] == rmse[std::size_t(best)]) ++last;
    e.best_time_offset_s = o.time_offset_s + (0.5 * (first + last) - steps) * kStep_s;
    e.ate_rmse_at_best_offset_m = rmse[std::size_t(best)];
}

}  // namespace

TrajectoryError evaluateTrajectory(const std::vector<TimedPose>& estimated, const std::vector<TimedPose>& ground_truth,
                                   const TrajectoryErrorOptions& options) {
    if (!std::isfinite(options.time_offset_s) ||
        !(options.max_time_offset_s >= 0.0 && options.max_time_offset_s <= 1.0))
        throw ConfigError(
            "trajectory error: the time offset must be finite and the offset search at most 1 s either way");
    const std::vector<TimedPose> est = sortedByTime(estimated), gt = sortedByTime(ground_truth);
    TrajectoryError e;
    computeAte(est, gt, options, e);
    computeRpe(est, gt, options, e);
    searchTimeOffset(est, gt, options, e);
    return e;
}

}  // namespace voxfuse
