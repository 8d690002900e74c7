// CPU/OpenMP loop of depth tracking; the per-pixel term is pointToPlaneTerm() in shared/DepthTracker.h.

#include <vector>

#include "NormalEquationsReduction_CPU.h"
#include "voxfuse/engines/DepthTracker.h"

namespace voxfuse::cpu {
namespace {

class DepthTrackerKernels_CPU final : public DepthTrackerKernels {
public:
    NormalEquations<double> accumulate(const DepthFrameLevel& level, const RenderState& model, const DepthTermParams& params,
                                       RobustKernel kernel, float kernel_scale_m) override {
        const Vec4f* vertices = level.vertices.host();
        const Vec4f* normals = level.normals.host();
        const Vec4f* model_points = model.points_world.host();
        const Vec4f* model_normals = model.normals_world.host();
        const int n = int(level.vertices.pixelCount());

        return accumulateNormalEquations(
            n, kernel, kernel_scale_m,
            [&](int i, float* J, float& r) { return pointToPlaneTerm(vertices[i], normals[i], model_points, model_normals, params, J, r); },
            partials_);
    }

private:
    std::vector<NormalEquations<double>> partials_;
};

}  // namespace

std::unique_ptr<DepthTrackerKernels> makeDepthTrackerKernels() { return std::make_unique<DepthTrackerKernels_CPU>(); }

}  // namespace voxfuse::cpu
