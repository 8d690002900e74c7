#pragma once
// Trajectory error against ground truth, as the TUM RGB-D benchmark measures it (Sturm et al., IROS
// 2012): the absolute trajectory error (ATE) after a rigid alignment, and the relative pose error
// (RPE) over a fixed time step, i.e. drift.

#include <vector>

#include "voxfuse/io/TrajectoryIO.h"

namespace voxfuse {

struct TrajectoryErrorOptions {
    double max_time_difference_s = 0.02;  // an estimated pose pairs with the nearest ground-truth pose within this
    double rpe_delta_s = 1.0;             // RPE compares motions over this time step
    double time_offset_s = 0.0;  // added to the estimated timestamps before pairing (TUM's evaluate_ate --offset)
    double max_time_offset_s =
        0.1;  // the best offset is searched within +-this of time_offset_s (0: no search; at most 1 s)
};

struct TrajectoryError {
    // ATE: estimated positions, moved by the rigid transform (rotation and translation, no scale; Horn /
    // Umeyama) that best fits them to the paired ground-truth positions, against those positions.
    int pairs = 0;            // estimated poses with a ground-truth partner
    double ate_rmse_m = 0.0;  // all ATE fields are NaN when fewer than 3 pairs exist
    double ate_mean_m = 0.0;
    double ate_median_m = 0.0;
    double ate_max_m = 0.0;
    Mat4f T_truth_estimate = Mat4f::identity();  // the alignment: estimated world to ground-truth world

    // RPE (TUM's evaluate_rpe with a time delta): for every estimated pose i, the estimated pose j
    // nearest to t_i + delta (within max_time_difference_s of it), both paired with ground truth. With
    // relative motions A = est_i^-1 est_j and B = gt_i^-1 gt_j, the error is E = A B^-1; its
    // translation length and rotation angle, divided by t_j - t_i, are averaged as RMSE.
    // Checked against the TUM scripts and evo (docs/BENCHMARKS.md); evaluate_rpe.py differs only in
    // which pairs its script keeps. evo's translational RPE reads higher: it takes E = B^-1 A, whose
    // translation |t_A - t_B| leaves out the rotation error that E = A B^-1 carries into it; the
    // angles agree.
    int rpe_pairs = 0;
    double rpe_trans_m_per_s = 0.0;  // NaN when rpe_pairs == 0
    double rpe_rot_deg_per_s = 0.0;

    // The clock offset that fits best: of the offsets (added to the estimated timestamps) within
    // max_time_offset_s of time_offset_s, in 1 ms steps, that leave at most 2% (at least one) of the
    // pairs without a partner (ground truth has gaps), the one with the least ATE RMSE, and that
    // RMSE. Poses pair by nearest timestamp, so neighbouring offsets often pair alike: the middle of
    // such a run is taken. A camera whose timestamps lag or lead the ground truth's clock (a
    // driver's delivery delay, another machine's clock) shows here, and how much of the ATE it
    // accounts for: a pose's error grows with the camera's speed times the offset. NaN without a
    // search or with fewer than 3 pairs.
    double best_time_offset_s = 0.0;
    double ate_rmse_at_best_offset_m = 0.0;
};

// Neither input needs to be sorted. ConfigError for a time offset that is not finite or a search
// wider than 1 s.
TrajectoryError evaluateTrajectory(const std::vector<TimedPose>& estimated, const std::vector<TimedPose>& ground_truth,
                                   const TrajectoryErrorOptions& options = {});

}  // namespace voxfuse
