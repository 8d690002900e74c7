// Trajectory error (ATE, RPE) against ground truth and TUM trajectory files.

#include <pybind11/stl.h>

#include <cmath>
#include <vector>

#include "Bindings.h"
#include "NumpyArrays.h"
#include "voxfuse/eval/TrajectoryError.h"
#include "voxfuse/io/TrajectoryIO.h"

namespace voxfuse::python {

// (timestamps (N,), poses (N, 4, 4)) as the library's timed poses.
std::vector<TimedPose> timedPoses(const py::handle& timestamps, const py::handle& poses, const char* what) {
    auto t = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(timestamps);
    auto p = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(poses);
    if (!t || t.ndim() != 1) throw py::value_error(std::string(what) + ": timestamps must be a 1-D array");
    if (!p || p.ndim() != 3 || p.shape(1) != 4 || p.shape(2) != 4 || p.shape(0) != t.shape(0))
        throw py::value_error(std::string(what) + ": poses must be an (N, 4, 4) array with one pose per timestamp");
    std::vector<TimedPose> out(std::size_t(t.shape(0)));
    const auto ta = t.unchecked<1>();
    const auto pa = p.unchecked<3>();
    for (py::ssize_t i = 0; i < t.shape(0); ++i) {
        out[i].timestamp_s = ta(i);
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) out[i].T_world_camera(r, c) = float(pa(i, r, c));
    }
    return out;
}

void bindTrajectory(py::module_& m) {
    m.def(
        "evaluate_trajectory",
        [](const py::handle& timestamps, const py::handle& poses, const py::handle& gt_timestamps,
           const py::handle& gt_poses, double max_time_difference, double time_offset, double max_time_offset) {
            TrajectoryErrorOptions o;
            o.max_time_difference_s = max_time_difference;
            o.time_offset_s = time_offset;
            o.max_time_offset_s = max_time_offset;
            const TrajectoryError e = evaluateTrajectory(timedPoses(timestamps, poses, "estimate"),
                                                         timedPoses(gt_timestamps, gt_poses, "ground truth"), o);
            py::dict d;
            d["pairs"] = e.pairs;
            d["ate_rmse_m"] = e.ate_rmse_m;
            d["ate_mean_m"] = e.ate_mean_m;
            d["ate_median_m"] = e.ate_median_m;
            d["ate_max_m"] = e.ate_max_m;
            d["rpe_pairs"] = e.rpe_pairs;
            d["rpe_trans_m_per_s"] = e.rpe_trans_m_per_s;
            d["rpe_rot_deg_per_s"] = e.rpe_rot_deg_per_s;
            d["T_truth_estimate"] = matrixToArray(e.T_truth_estimate);
            d["best_time_offset_s"] = e.best_time_offset_s;
            d["ate_rmse_at_best_time_offset_m"] = e.ate_rmse_at_best_offset_m;
            return d;
        },
        py::arg("timestamps"), py::arg("poses"), py::arg("gt_timestamps"), py::arg("gt_poses"),
        py::arg("max_time_difference") = 0.02, py::arg("time_offset") = 0.0, py::arg("max_time_offset") = 0.1,
        "ATE and RPE of camera-to-world poses (N, 4, 4) against ground truth, after a rigid alignment (TUM's\n"
        "evaluate_ate / evaluate_rpe); poses pair by nearest timestamp within max_time_difference seconds,\n"
        "after time_offset (s) is added to their timestamps. best_time_offset_s is the offset within\n"
        "max_time_offset of it (1 ms steps) with the least ATE, ate_rmse_at_best_time_offset_m that ATE\n"
        "(NaN when max_time_offset is 0).");
    m.def(
        "read_tum_trajectory", [](const std::string& path) { return timedPosesToArrays(readTumTrajectory(path)); },
        py::arg("path"),
        "Reads a TUM trajectory file ('timestamp tx ty tz qx qy qz qw'): (timestamps (N,), poses (N, 4, 4)).");
    m.def(
        "write_tum_trajectory",
        [](const std::string& path, const py::handle& timestamps, const py::handle& poses) {
            writeTumTrajectory(path, timedPoses(timestamps, poses, "trajectory"));
        },
        py::arg("path"), py::arg("timestamps"), py::arg("poses"), "Writes a TUM trajectory file.");
}

}  // namespace voxfuse::python
