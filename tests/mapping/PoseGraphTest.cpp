// PoseGraph: closed-form solutions of small graphs, a wrong loop edge rejected, odometry alone left as
// it is, malformed graphs refused, and the optimiser's thread giving what a direct solve gives.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "voxfuse/core/EigenInterop.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/mapping/PoseGraph.h"

namespace voxfuse {
namespace {

Mat4f pose(float yaw_rad, Eigen::Vector3f t) {
    Eigen::Matrix4f T = Eigen::Matrix4f::Identity();
    T.topLeftCorner<3, 3>() = Eigen::AngleAxisf(yaw_rad, Eigen::Vector3f::UnitZ()).toRotationMatrix();
    T.topRightCorner<3, 1>() = t;
    return toMat4f(T);
}

Mat4f relative(const Mat4f& T_world_a, const Mat4f& T_world_b) { return rigidInverse(T_world_a) * T_world_b; }

float distanceM(const Mat4f& a, const Mat4f& b) { return (toEigen(a.translation()) - toEigen(b.translation())).norm(); }

PoseGraphEdge edge(int from, int to, const Mat4f& T_from_to, bool loop, float sigma_translation_m = 0.01f) {
    PoseGraphEdge e;
    e.sigma_translation_m = sigma_translation_m;
    e.from = from;
    e.to = to;
    e.T_from_to = T_from_to;
    e.loop = loop;
    return e;
}

PoseGraph chainWithLoop() {
    PoseGraph g;
    for (int i = 0; i < 5; ++i) g.addNode(pose(0.f, {1.1f * i, 0.f, 0.f}));
    for (int i = 0; i < 4; ++i) g.addEdge(edge(i, i + 1, pose(0.f, {1.1f, 0.f, 0.f}), false, 0.1f));
    g.addEdge(edge(0, 4, pose(0.f, {4.0f, 0.f, 0.f}), true, 0.1f));
    return g;
}

// Nodes on a line, 1 m apart, odometry measuring 1.1 m each (4 edges), a loop edge measuring 4 m from
// the first to the last, all with a standard deviation of 0.1 m: least squares puts every step at
// d = (4 * 1.1 + 4 * 4) / (4 + 16) = 1.02 m, so the last node at 4.08 m, and every edge 0.8
// standard deviations off (chi-square 0.64), well within the loop's rejection bound.
TEST(PoseGraphTest, ChainWithLoopMeetsTheLeastSquaresSolution) {
#ifndef VOXFUSE_WITH_CERES
    GTEST_SKIP() << "built without Ceres";
#endif
    const PoseGraph g = chainWithLoop();
    const PoseGraphResult r = g.optimise();
    ASSERT_EQ(r.T_world_node.size(), 5u);
    for (int i = 0; i < 5; ++i) {
        EXPECT_NEAR(r.T_world_node[i](0, 3), 1.02f * i, 1e-4f) << "node " << i;
        EXPECT_NEAR(r.T_world_node[i](1, 3), 0.f, 1e-5f);
    }
    EXPECT_EQ(r.rejectedLoops(), 0);
    for (double chi2 : r.edge_chi2) EXPECT_NEAR(chi2, 0.64, 1e-3);
    EXPECT_LT(r.final_cost, r.initial_cost);
}

// A circuit of 12 nodes on a 3 m circle whose odometry over-turns by 0.5 degrees a step (the drift of
// a tracker): the last node ends far from where it is. A correct loop edge back to the first brings
// every node within a fraction of that error; a second, wrong loop edge (the revisit of a place
// that looks alike 1.5 m away) is rejected and changes nothing.
TEST(PoseGraphTest, DriftingCircuitIsClosedAndAWrongLoopIsRejected) {
#ifndef VOXFUSE_WITH_CERES
    GTEST_SKIP() << "built without Ceres";
#endif
    const int n = 12;
    const float radius_m = 3.f, step_rad = 2.f * float(M_PI) / n, drift_rad = 0.5f * float(M_PI) / 180.f;
    std::vector<Mat4f> truth;
    for (int i = 0; i < n; ++i) {
        const float a = step_rad * i;
        truth.push_back(pose(a + float(M_PI) / 2, {radius_m * std::cos(a), radius_m * std::sin(a), 0.f}));
    }
    PoseGraph g;
    Mat4f chained = truth[0];
    g.addNode(chained);
    std::vector<Mat4f> odometry;
    for (int i = 0; i + 1 < n; ++i) {
        const Mat4f measured = relative(truth[i], truth[i + 1]) * pose(drift_rad, {0.f, 0.f, 0.f});
        chained = chained * measured;
        g.addNode(chained);
        g.addEdge(edge(i, i + 1, measured, false));
    }
    const float drift_error_m = distanceM(chained, truth[n - 1]);
    ASSERT_GT(drift_error_m, 0.15f);

    PoseGraph right = g;
    right.addEdge(edge(n - 1, 0, relative(truth[n - 1], truth[0]), true));
    const PoseGraphResult closed = right.optimise();
    float worst_m = 0.f;
    for (int i = 0; i < n; ++i) worst_m = std::max(worst_m, distanceM(closed.T_world_node[i], truth[i]));
    EXPECT_LT(worst_m, 0.25f * drift_error_m);
    EXPECT_EQ(closed.rejectedLoops(), 0);

    PoseGraph both = right;
    both.addEdge(edge(n / 2, 0, relative(truth[n / 2], truth[0]) * pose(0.f, {1.5f, 0.f, 0.f}), true));
    const PoseGraphResult robust = both.optimise();
    EXPECT_FALSE(robust.edge_rejected[n - 1]);
    EXPECT_TRUE(robust.edge_rejected[n]);
    EXPECT_EQ(robust.rejectedLoops(), 1);
    for (int i = 0; i < n; ++i) EXPECT_LT(distanceM(robust.T_world_node[i], closed.T_world_node[i]), 1e-3f) << i;
}

// Without loops the graph is a tree: its solution is the odometry, chained from the fixed first node.
TEST(PoseGraphTest, OdometryAloneIsLeftAsItIs) {
#ifndef VOXFUSE_WITH_CERES
    GTEST_SKIP() << "built without Ceres";
#endif
    PoseGraph g;
    Mat4f chained = pose(0.3f, {0.5f, -1.f, 2.f});
    g.addNode(chained);
    for (int i = 0; i < 6; ++i) {
        const Mat4f step = pose(0.1f * i, {0.2f, 0.05f * i, 0.01f});
        chained = chained * step;
        g.addNode(pose(0.f, {0.f, 0.f, 0.f}));  // a poor start: the solve must still find the chain
        g.addEdge(edge(i, i + 1, step, false));
    }
    const PoseGraphResult r = g.optimise();
    EXPECT_LT(distanceM(r.T_world_node[6], chained), 1e-4f);
    EXPECT_LT(distanceM(r.T_world_node[0], pose(0.3f, {0.5f, -1.f, 2.f})), 1e-6f);
    for (double chi2 : r.edge_chi2) EXPECT_LT(chi2, 1e-6);
}

TEST(PoseGraphTest, MalformedGraphsAreRefused) {
    PoseGraph g;
    g.addNode(Mat4f::identity());
    g.addNode(Mat4f::identity());
    EXPECT_THROW(g.addEdge(edge(0, 2, Mat4f::identity(), false)), ConfigError);
    EXPECT_THROW(g.addEdge(edge(1, 1, Mat4f::identity(), false)), ConfigError);
    PoseGraphEdge bad_sigma = edge(0, 1, Mat4f::identity(), false);
    bad_sigma.sigma_rotation_rad = 0.f;
    EXPECT_THROW(g.addEdge(bad_sigma), ConfigError);
    Mat4f scaled = Mat4f::identity();
    scaled(0, 0) = 2.f;
    EXPECT_THROW(g.addEdge(edge(0, 1, scaled, false)), ConfigError);
    EXPECT_THROW(g.addNode(scaled), ConfigError);
    EXPECT_THROW(g.optimise(), ConfigError);  // node 1 hangs on nothing
    EXPECT_EQ(g.edgeCount(), 0);
}

TEST(PoseGraphTest, OptimiserThreadGivesTheDirectSolution) {
#ifndef VOXFUSE_WITH_CERES
    GTEST_SKIP() << "built without Ceres";
#endif
    const PoseGraph g = chainWithLoop();
    PoseGraphOptimiser optimiser;
    PoseGraphResult r;
    EXPECT_EQ(optimiser.latest(r), 0);
    EXPECT_EQ(optimiser.solveStats().solves, 0);
    optimiser.submit(g);
    optimiser.waitIdle();
    ASSERT_EQ(optimiser.latest(r), 1);
    const PoseGraphResult direct = g.optimise();
    for (int i = 0; i < 5; ++i) EXPECT_EQ(distanceM(r.T_world_node[i], direct.T_world_node[i]), 0.f);
    // Its time is counted as the solve measured it.
    PoseGraphResult second;
    optimiser.submit(g);
    optimiser.waitIdle();
    ASSERT_EQ(optimiser.latest(second), 2);
    const PoseGraphSolveStats stats = optimiser.solveStats();
    EXPECT_EQ(stats.solves, 2);
    EXPECT_DOUBLE_EQ(stats.total_ms, r.solve_ms + second.solve_ms);
    EXPECT_DOUBLE_EQ(stats.max_ms, std::max(r.solve_ms, second.solve_ms));
}

}  // namespace
}  // namespace voxfuse
