// PoseGraph's bookkeeping and the optimiser's thread; the solve itself is PoseGraphSolve_Ceres.cpp
// (or PoseGraphSolve_NoCeres.cpp in a build without Ceres).

#include "voxfuse/mapping/PoseGraph.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "PoseGraphSolve.h"
#include "io/TextParsing.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {

int PoseGraphResult::rejectedLoops() const {
    int n = 0;
    for (bool r : edge_rejected) n += r ? 1 : 0;
    return n;
}

int PoseGraph::addNode(const Mat4f& T_world_node_initial) {
    const std::string problem = text::rigidPoseProblem(T_world_node_initial.m);
    if (!problem.empty()) throw ConfigError("pose graph node " + std::to_string(nodes_.size()) + ": " + problem);
    nodes_.push_back(T_world_node_initial);
    return static_cast<int>(nodes_.size()) - 1;
}

void PoseGraph::setNode(int node, const Mat4f& T_world_node) {
    if (node < 0 || node >= nodeCount()) throw ConfigError("pose graph: no node " + std::to_string(node));
    const std::string problem = text::rigidPoseProblem(T_world_node.m);
    if (!problem.empty()) throw ConfigError("pose graph node " + std::to_string(node) + ": " + problem);
    nodes_[node] = T_world_node;
}

void PoseGraph::addEdge(const PoseGraphEdge& e) {
    const std::string name = "pose graph edge " + std::to_string(e.from) + "-" + std::to_string(e.to);
    if (e.from < 0 || e.from >= nodeCount() || e.to < 0 || e.to >= nodeCount())
        throw ConfigError(name + ": no such node (the graph has " + std::to_string(nodeCount()) + ")");
    if (e.from == e.to) throw ConfigError(name + ": an edge joins two different nodes");
    if (!(e.sigma_translation_m > 0.f) || !(e.sigma_rotation_rad > 0.f) || !std::isfinite(e.sigma_translation_m) ||
        !std::isfinite(e.sigma_rotation_rad))
        throw ConfigError(name + ": standard deviations must be positive and finite");
    const std::string problem = text::rigidPoseProblem(e.T_from_to.m);
    if (!problem.empty()) throw ConfigError(name + ": " + problem);
    edges_.push_back(e);
}

PoseGraphResult PoseGraph::optimise(const PoseGraphSettings& settings) const {
    if (nodes_.empty()) return {};
    // Every node must hang on node 0 through edges, or its pose is not determined.
    std::vector<int> component(nodes_.size());
    for (std::size_t i = 0; i < component.size(); ++i) component[i] = static_cast<int>(i);
    const auto root = [&](int i) {
        while (component[i] != i) i = component[i] = component[component[i]];
        return i;
    };
    for (const PoseGraphEdge& e : edges_) component[root(e.from)] = root(e.to);
    for (int i = 1; i < nodeCount(); ++i)
        if (root(i) != root(0))
            throw ConfigError("pose graph: node " + std::to_string(i) + " is joined to node 0 by no chain of edges");
    return solvePoseGraph(nodes_, edges_, settings);
}

PoseGraphOptimiser::PoseGraphOptimiser(const PoseGraphSettings& settings)
    : settings_(settings), thread_([this] { run(); }) {}

PoseGraphOptimiser::~PoseGraphOptimiser() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
}

void PoseGraphOptimiser::submit(const PoseGraph& graph) {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        next_ = graph;
        pending_ = true;
    }
    wake_.notify_all();
}

int PoseGraphOptimiser::latest(PoseGraphResult& result) const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (error_) std::rethrow_exception(error_);
    if (stats_.solves > 0) result = latest_;
    return stats_.solves;
}

int PoseGraphOptimiser::solvedCount() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return stats_.solves;
}

PoseGraphSolveStats PoseGraphOptimiser::solveStats() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return stats_;
}

void PoseGraphOptimiser::waitIdle() {
    std::unique_lock<std::mutex> lock(mutex_);
    idle_.wait(lock, [this] { return !pending_ && !busy_; });
    if (error_) std::rethrow_exception(error_);
}

void PoseGraphOptimiser::run() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
        wake_.wait(lock, [this] { return stop_ || pending_; });
        if (stop_) return;
        PoseGraph graph = std::move(next_);
        pending_ = false;
        busy_ = true;
        lock.unlock();
        PoseGraphResult result;
        std::exception_ptr error;
        try {
            result = graph.optimise(settings_);
        } catch (...) {
            error = std::current_exception();
        }
        lock.lock();
        busy_ = false;
        if (error)
            error_ = error;
        else {
            ++stats_.solves;
            stats_.total_ms += result.solve_ms;
            stats_.max_ms = std::max(stats_.max_ms, result.solve_ms);
            latest_ = std::move(result);
        }
        idle_.notify_all();
    }
}

}  // namespace voxfuse
