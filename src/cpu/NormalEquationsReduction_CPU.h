#pragma once
// The CPU reduction every Gauss-Newton tracker shares: n per-element terms, each giving a Jacobian
// row J[6] and residual r (or nothing), summed into one 6x6 system with robust weights.

#include <omp.h>

#include <vector>

#include "voxfuse/shared/NormalEquations.h"
#include "voxfuse/shared/RobustKernel.h"

namespace voxfuse::cpu {

// `term(i, J, r)` returns false when element i gives no term. Per-thread partial sums are added in
// thread order afterwards, so the result does not depend on which thread finished first (an omp
// reduction clause would not promise that). `partials` is scratch kept by the caller between calls.
template <class TermFn>
NormalEquations<double> accumulateNormalEquations(int n, RobustKernel kernel, float kernel_scale, TermFn term,
                                                  std::vector<NormalEquations<double>>& partials) {
    const int threads = omp_get_max_threads();
    partials.assign(std::size_t(threads), NormalEquations<double>::zero());
#pragma omp parallel num_threads(threads)
    {
        NormalEquations<double> local = NormalEquations<double>::zero();
#pragma omp for schedule(static) nowait
        for (int i = 0; i < n; ++i) {
            float J[6], r;
            if (!term(i, J, r)) continue;
            const float w = robustWeight(kernel, r, kernel_scale);
            if (w > 0.f) local.addTerm(J, r, w);
        }
        partials[std::size_t(omp_get_thread_num())] = local;
    }
    NormalEquations<double> total = NormalEquations<double>::zero();
    for (const NormalEquations<double>& p : partials) total.add(p);
    return total;
}

}  // namespace voxfuse::cpu
