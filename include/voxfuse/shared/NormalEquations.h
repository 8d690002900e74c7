#pragma once
// The 6x6 Gauss-Newton system (J^T W J) x = -(J^T W r) of a pose update, accumulated one residual at
// a time. Only the 21 upper-triangle entries of the symmetric matrix are stored. The scalar is a
// template parameter: the CPU layer sums hundreds of thousands of terms per thread in double.
//
// Parameter order everywhere in the trackers: x = (omega, v), rotation (radians) then translation
// (metres), a right-multiplied update of the camera pose: T_world_camera * exp(x).

#include "voxfuse/core/Platform.h"

namespace voxfuse {

template <typename T>
struct NormalEquations {
    T hessian[21];    // J^T W J, upper triangle row by row: (0,0) (0,1) .. (0,5) (1,1) .. (5,5)
    T gradient[6];    // J^T W r
    T weighted_cost;  // sum of w r^2
    T squared_sum;    // sum of r^2 (unweighted), for the RMS residual
    int count;        // number of terms (inliers)

    VF_HOST_DEVICE static NormalEquations zero() {
        NormalEquations e;
        for (int i = 0; i < 21; ++i) e.hessian[i] = T(0);
        for (int i = 0; i < 6; ++i) e.gradient[i] = T(0);
        e.weighted_cost = e.squared_sum = T(0);
        e.count = 0;
        return e;
    }

    // Adds one residual r with Jacobian row J (dr/dx) and weight w.
    VF_HOST_DEVICE void addTerm(const float J[6], float r, float w) {
        int k = 0;
        for (int i = 0; i < 6; ++i) {
            const T wj = T(w) * T(J[i]);
            for (int j = i; j < 6; ++j) hessian[k++] += wj * T(J[j]);
            gradient[i] += wj * T(r);
        }
        weighted_cost += T(w) * T(r) * T(r);
        squared_sum += T(r) * T(r);
        ++count;
    }

    // Adds `o` scaled by `s` (s weighs one kind of residual against another, e.g. colour vs depth).
    VF_HOST_DEVICE void add(const NormalEquations& o, T s = T(1)) {
        for (int i = 0; i < 21; ++i) hessian[i] += s * o.hessian[i];
        for (int i = 0; i < 6; ++i) gradient[i] += s * o.gradient[i];
        weighted_cost += s * o.weighted_cost;
        squared_sum += o.squared_sum;
        count += o.count;
    }

    // Entry (row, col) of the full symmetric matrix.
    VF_HOST_DEVICE T at(int row, int col) const {
        if (row > col) {
            const int t = row;
            row = col;
            col = t;
        }
        return hessian[row * 6 - row * (row - 1) / 2 + (col - row)];
    }
};

}  // namespace voxfuse
