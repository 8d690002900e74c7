// PoseGraph in a build without Ceres: graphs can be built, a solve says what to install.

#include "PoseGraphSolve.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {

bool poseGraphAvailable() { return false; }

PoseGraphResult solvePoseGraph(const std::vector<Mat4f>&, const std::vector<PoseGraphEdge>&, const PoseGraphSettings&) {
    throw ConfigError("this VoxFuse build has no pose graph optimisation (install libceres-dev and rebuild)");
}

}  // namespace voxfuse
