// CPU/OpenMP loop of depth tracking; the per-pixel term is pointToPlaneTerm() in shared/DepthTracker.h.

#include <omp.h>

#include <vector>

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

        // Per-thread partial sums, added in thread order afterwards: the result does not depend on
        // which thread finished first (an omp reduction clause would not promise that).
        const int threads = omp_get_max_threads();
        partials_.assign(std::size_t(threads), NormalEquations<double>::zero());
#pragma omp parallel num_threads(threads)
        {
            NormalEquations<double> local = NormalEquations<double>::zero();
#pragma omp for schedule(static) nowait
            for (int i = 0; i < n; ++i) {
                float J[6], r;
                if (!pointToPlaneTerm(vertices[i], normals[i], model_points, model_normals, params, J, r)) continue;
                const float w = robustWeight(kernel, r, kernel_scale_m);
                if (w > 0.f) local.addTerm(J, r, w);
            }
            partials_[std::size_t(omp_get_thread_num())] = local;
        }
        NormalEquations<double> total = NormalEquations<double>::zero();
        for (const NormalEquations<double>& p : partials_) total.add(p);
        return total;
    }

private:
    std::vector<NormalEquations<double>> partials_;
};

}  // namespace

std::unique_ptr<DepthTrackerKernels> makeDepthTrackerKernels() { return std::make_unique<DepthTrackerKernels_CPU>(); }

}  // namespace voxfuse::cpu
