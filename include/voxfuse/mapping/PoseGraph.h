#pragma once
// The poses of submaps (nodes) optimised over measured relative poses (edges): odometry between
// submaps the camera went from one to the next, and loop closures between a submap and one it came
// back to. Solved with Ceres (Debian: libceres-dev); a build without it throws ConfigError on
// optimise(). Loop edges are robust: a Cauchy loss first down-weights an edge that disagrees with the
// rest, then loop edges still beyond the chi-square bound are dropped and the graph solved again
// without them, so one wrong loop never bends the map. Node 0 holds the world frame fixed.

#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

#include "voxfuse/core/Math.h"

namespace voxfuse {

// Whether this build can optimise pose graphs (it has Ceres).
bool poseGraphAvailable();

struct PoseGraphEdge {
    int from = 0;
    int to = 0;
    Mat4f T_from_to = Mat4f::identity();  // the measured pose of node `to` in node `from`'s frame
    // Standard deviations of the measurement: of its translation (per axis, in `from`'s frame) and of
    // its rotation (per axis of the rotation vector).
    float sigma_translation_m = 0.01f;
    float sigma_rotation_rad = 0.01f;
    bool loop = false;  // loop closures are robust and may be rejected; odometry is trusted
};

struct PoseGraphSettings {
    // The Cauchy loss's scale on a loop edge's whitened residual (in standard deviations): residuals
    // well beyond it weigh like their logarithm.
    double loop_loss_scale = 3.0;
    // A loop edge whose squared Mahalanobis residual at the robust solution exceeds this is rejected:
    // 22.46 is the chi-square distribution's 99.9% point for 6 degrees of freedom, so a right edge
    // is dropped once in a thousand.
    double loop_rejection_chi2 = 22.46;
    int max_iterations = 100;
};

struct PoseGraphResult {
    std::vector<Mat4f> T_world_node;  // the optimised poses, node by node
    std::vector<double> edge_chi2;    // each edge's squared Mahalanobis residual at the solution
    std::vector<bool> edge_rejected;  // loop edges dropped as outliers (odometry is never)
    int iterations = 0;               // of both solves
    double initial_cost = 0.0;        // half the sum of squared whitened residuals, before and after
    double final_cost = 0.0;
    double solve_ms = 0.0;
    int rejectedLoops() const;
};

class PoseGraph {
public:
    // Returns the node's index. The first node added is held fixed.
    int addNode(const Mat4f& T_world_node_initial);
    // ConfigError for a node index that does not exist, a self-edge, a non-positive sigma or a
    // measurement that is no rigid pose.
    void addEdge(const PoseGraphEdge& edge);
    int nodeCount() const { return static_cast<int>(nodes_.size()); }
    int edgeCount() const { return static_cast<int>(edges_.size()); }
    const std::vector<Mat4f>& nodes() const { return nodes_; }
    const std::vector<PoseGraphEdge>& edges() const { return edges_; }
    // Replaces a node's initial pose (e.g. with the last solution, so the next solve starts near it).
    void setNode(int node, const Mat4f& T_world_node);

    PoseGraphResult optimise(const PoseGraphSettings& settings = {}) const;

private:
    std::vector<Mat4f> nodes_;
    std::vector<PoseGraphEdge> edges_;
};

// What the optimiser's thread has spent: its solves and their time (PoseGraphResult::solve_ms).
struct PoseGraphSolveStats {
    int solves = 0;
    double total_ms = 0.0;
    double max_ms = 0.0;
};

// Solves pose graphs on a thread of its own, so that the frame loop never waits for a solve: submit()
// hands over a copy of the graph (a newer graph replaces one that has not started), and latest()
// returns the newest finished solution.
class PoseGraphOptimiser {
public:
    explicit PoseGraphOptimiser(const PoseGraphSettings& settings = {});
    ~PoseGraphOptimiser();
    PoseGraphOptimiser(const PoseGraphOptimiser&) = delete;
    PoseGraphOptimiser& operator=(const PoseGraphOptimiser&) = delete;

    void submit(const PoseGraph& graph);
    // The newest solution and the number of graphs solved so far (0: none yet, `result` untouched).
    // A solve that threw is reported by rethrowing its error here.
    int latest(PoseGraphResult& result) const;
    // The number of graphs solved so far, without copying the solution.
    int solvedCount() const;
    PoseGraphSolveStats solveStats() const;
    // Blocks until every submitted graph is solved.
    void waitIdle();

private:
    void run();

    PoseGraphSettings settings_;
    mutable std::mutex mutex_;
    std::condition_variable wake_;
    std::condition_variable idle_;
    bool stop_ = false;
    bool pending_ = false;
    bool busy_ = false;
    PoseGraph next_;
    PoseGraphResult latest_;
    PoseGraphSolveStats stats_;  // stats_.solves: the graphs solved so far
    std::exception_ptr error_;
    std::thread thread_;
};

}  // namespace voxfuse
