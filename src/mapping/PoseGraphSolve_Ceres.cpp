// PoseGraph::optimise with Ceres: each node a translation and a unit quaternion (on Ceres's quaternion
// manifold), each edge a 6-vector residual (the translation error, and twice the vector part of the
// rotation error, each divided by its standard deviation), automatic derivatives, sparse Cholesky.

#include <ceres/ceres.h>

#include <Eigen/Geometry>
#include <memory>

#include "PoseGraphSolve.h"
#include "voxfuse/core/Timer.h"

namespace voxfuse {
namespace {

struct NodeParameters {
    double t[3];
    double q[4];  // x, y, z, w (Eigen's order)
};

NodeParameters toParameters(const Mat4f& T) {
    Eigen::Matrix3d R;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) R(r, c) = T(r, c);
    Eigen::Quaterniond q(R);
    q.normalize();
    return {{T(0, 3), T(1, 3), T(2, 3)}, {q.x(), q.y(), q.z(), q.w()}};
}

Mat4f toPose(const NodeParameters& p) {
    const Eigen::Matrix3d R = Eigen::Quaterniond(p.q[3], p.q[0], p.q[1], p.q[2]).normalized().toRotationMatrix();
    Mat4f T = Mat4f::identity();
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) T(r, c) = static_cast<float>(R(r, c));
        T(r, 3) = static_cast<float>(p.t[r]);
    }
    return T;
}

// The residual of one edge: the pose of `to` in `from` as the nodes have it, against the measurement.
struct EdgeResidual {
    explicit EdgeResidual(const PoseGraphEdge& e) : measured(toParameters(e.T_from_to)) {
        inv_sigma_t = 1.0 / e.sigma_translation_m;
        inv_sigma_r = 1.0 / e.sigma_rotation_rad;
    }

    template <class T>
    bool operator()(const T* t_from, const T* q_from, const T* t_to, const T* q_to, T* residual) const {
        using Vec3 = Eigen::Matrix<T, 3, 1>;
        const Eigen::Map<const Vec3> pa(t_from), pb(t_to);
        const Eigen::Map<const Eigen::Quaternion<T>> qa(q_from), qb(q_to);
        const Eigen::Quaternion<T> qa_inv = qa.conjugate();
        const Eigen::Quaternion<T> q_ab = qa_inv * qb;
        const Vec3 t_ab = qa_inv * (pb - pa);
        const Eigen::Quaternion<T> q_meas(T(measured.q[3]), T(measured.q[0]), T(measured.q[1]), T(measured.q[2]));
        const Eigen::Quaternion<T> dq = q_meas.conjugate() * q_ab;
        // dq and -dq are one rotation: take the one near identity.
        const T sign = dq.w() < T(0) ? T(-1) : T(1);
        for (int i = 0; i < 3; ++i) {
            residual[i] = (t_ab[i] - T(measured.t[i])) * T(inv_sigma_t);
            residual[3 + i] = T(2) * sign * dq.vec()[i] * T(inv_sigma_r);
        }
        return true;
    }

    NodeParameters measured;
    double inv_sigma_t;
    double inv_sigma_r;
};

double edgeChi2(const PoseGraphEdge& e, const NodeParameters& from, const NodeParameters& to) {
    double r[6];
    const EdgeResidual residual(e);
    residual(from.t, from.q, to.t, to.q, r);
    double s = 0.0;
    for (double v : r) s += v * v;
    return s;
}

// One solve over the edges not in `skip`; loop edges robust when `robust`. Updates `nodes` in place.
ceres::Solver::Summary solveOnce(std::vector<NodeParameters>& nodes, const std::vector<PoseGraphEdge>& edges,
                                 const std::vector<bool>& skip, bool robust, const PoseGraphSettings& settings) {
    ceres::Problem problem;
    for (std::size_t i = 0; i < edges.size(); ++i) {
        if (skip[i]) continue;
        const PoseGraphEdge& e = edges[i];
        auto* cost = new ceres::AutoDiffCostFunction<EdgeResidual, 6, 3, 4, 3, 4>(new EdgeResidual(e));
        ceres::LossFunction* loss = robust && e.loop ? new ceres::CauchyLoss(settings.loop_loss_scale) : nullptr;
        problem.AddResidualBlock(cost, loss, nodes[e.from].t, nodes[e.from].q, nodes[e.to].t, nodes[e.to].q);
    }
    for (NodeParameters& n : nodes)
        if (problem.HasParameterBlock(n.q)) problem.SetManifold(n.q, new ceres::EigenQuaternionManifold);
    if (problem.HasParameterBlock(nodes[0].t)) {
        problem.SetParameterBlockConstant(nodes[0].t);
        problem.SetParameterBlockConstant(nodes[0].q);
    }
    ceres::Solver::Options options;
    options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    options.max_num_iterations = settings.max_iterations;
    options.num_threads = 1;  // off the frame loop's threads
    options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    return summary;
}

}  // namespace

bool poseGraphAvailable() { return true; }

PoseGraphResult solvePoseGraph(const std::vector<Mat4f>& T_world_nodes, const std::vector<PoseGraphEdge>& edges,
                               const PoseGraphSettings& settings) {
    const Timer timer;
    std::vector<NodeParameters> nodes;
    nodes.reserve(T_world_nodes.size());
    for (const Mat4f& T : T_world_nodes) nodes.push_back(toParameters(T));

    PoseGraphResult result;
    result.edge_rejected.assign(edges.size(), false);
    if (!edges.empty()) {
        const ceres::Solver::Summary robust = solveOnce(nodes, edges, result.edge_rejected, true, settings);
        result.initial_cost = robust.initial_cost;
        result.iterations = static_cast<int>(robust.iterations.size());
        for (std::size_t i = 0; i < edges.size(); ++i)
            result.edge_rejected[i] = edges[i].loop && edgeChi2(edges[i], nodes[edges[i].from], nodes[edges[i].to]) >
                                                           settings.loop_rejection_chi2;
        // The edges kept, at full weight: an outlier no longer pulls the inliers down.
        const ceres::Solver::Summary final_solve = solveOnce(nodes, edges, result.edge_rejected, false, settings);
        result.iterations += static_cast<int>(final_solve.iterations.size());
        result.final_cost = final_solve.final_cost;
    }
    result.edge_chi2.reserve(edges.size());
    for (const PoseGraphEdge& e : edges) result.edge_chi2.push_back(edgeChi2(e, nodes[e.from], nodes[e.to]));
    result.T_world_node.reserve(nodes.size());
    for (const NodeParameters& n : nodes) result.T_world_node.push_back(toPose(n));
    result.solve_ms = timer.elapsedMs();
    return result;
}

}  // namespace voxfuse
