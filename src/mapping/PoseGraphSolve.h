#pragma once
// The solve behind PoseGraph::optimise (one implementation per build: with or without Ceres). The
// graph is checked (edges valid, every node joined to node 0) before it gets here.

#include <vector>

#include "voxfuse/mapping/PoseGraph.h"

namespace voxfuse {

PoseGraphResult solvePoseGraph(const std::vector<Mat4f>& T_world_nodes, const std::vector<PoseGraphEdge>& edges,
                               const PoseGraphSettings& settings);

}  // namespace voxfuse
