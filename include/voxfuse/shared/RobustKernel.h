#pragma once
// Iteratively reweighted least squares: the weight w(r) = rho'(r) / r of a robust cost rho, so that a
// Gauss-Newton step on sum w r^2 is a step on sum rho(r). `scale` is in the residual's unit.

#include <cmath>

#include "voxfuse/core/Platform.h"

namespace voxfuse {

enum class RobustKernel : int {
    None,   // least squares: w = 1
    Huber,  // quadratic within scale, linear beyond (keeps every term, caps the pull of outliers)
    Tukey   // biweight: smooth, zero weight beyond scale (ignores gross outliers entirely)
};

VF_HOST_DEVICE inline float robustWeight(RobustKernel kernel, float r, float scale) {
    const float a = fabsf(r);
    switch (kernel) {
        case RobustKernel::Huber:
            return a <= scale ? 1.f : scale / a;
        case RobustKernel::Tukey: {
            if (a >= scale) return 0.f;
            const float u = 1.f - (r / scale) * (r / scale);
            return u * u;
        }
        case RobustKernel::None:
            break;
    }
    return 1.f;
}

}  // namespace voxfuse
