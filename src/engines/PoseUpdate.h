#pragma once
// Host-side algebra shared by the trackers: solving the 6x6 normal equations (Eigen LDLT) for the
// parameters a level optimises, applying the update on SE(3) with the exponential map, and measuring
// the system's condition and the size of a motion. Poses are kept in double on the host so that many
// small updates do not accumulate float round-off; the device layers get Mat4f copies.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

#include "voxfuse/core/Math.h"
#include "voxfuse/engines/TrackerSettings.h"
#include "voxfuse/shared/NormalEquations.h"

namespace voxfuse::pose {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

inline Eigen::Matrix4d toEigenD(const Mat4f& m) {
    Eigen::Matrix4d e;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) e(r, c) = m(r, c);
    return e;
}
inline Mat4f toMat4f(const Eigen::Matrix4d& e) {
    Mat4f m;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m(r, c) = float(e(r, c));
    return m;
}

inline Matrix6d fullMatrix(const NormalEquations<double>& eq) {
    Matrix6d H;
    for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c) H(r, c) = eq.at(r, c);
    return H;
}

inline Eigen::Matrix3d skew(const Eigen::Vector3d& w) {
    Eigen::Matrix3d S;
    S << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
    return S;
}

// exp of the twist x = (omega, v): rotation by |omega| about omega, translation V(omega) v.
inline Eigen::Matrix4d expSE3(const Vector6d& x) {
    const Eigen::Vector3d w = x.head<3>(), v = x.tail<3>();
    const double theta = w.norm();
    const Eigen::Matrix3d W = skew(w), W2 = W * W;
    double a, b, c;  // sin(t)/t, (1 - cos t)/t^2, (t - sin t)/t^3
    if (theta < 1e-5) {
        a = 1.0 - theta * theta / 6.0;
        b = 0.5 - theta * theta / 24.0;
        c = 1.0 / 6.0 - theta * theta / 120.0;
    } else {
        a = std::sin(theta) / theta;
        b = (1.0 - std::cos(theta)) / (theta * theta);
        c = (theta - std::sin(theta)) / (theta * theta * theta);
    }
    Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
    T.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() + a * W + b * W2;
    T.topRightCorner<3, 1>() = (Eigen::Matrix3d::Identity() + b * W + c * W2) * v;
    return T;
}

// T * exp(x), with the rotation re-orthonormalised (through a unit quaternion) against drift.
inline Eigen::Matrix4d applyUpdate(const Eigen::Matrix4d& T, const Vector6d& x) {
    Eigen::Matrix4d r = T * expSE3(x);
    const Eigen::Quaterniond q(Eigen::Matrix3d(r.topLeftCorner<3, 3>()));
    r.topLeftCorner<3, 3>() = q.normalized().toRotationMatrix();
    return r;
}

// Solves (H + lambda diag(H)) x = -g for the parameters `motion` selects (the others stay 0).
// False when the system is singular or the result not finite.
inline bool solveUpdate(const NormalEquations<double>& eq, LevelMotion motion, double lambda, Vector6d& x) {
    const int first = motion == LevelMotion::Translation ? 3 : 0;
    const int n = motion == LevelMotion::Both ? 6 : 3;
    const Matrix6d H6 = fullMatrix(eq);
    Eigen::MatrixXd H = H6.block(first, first, n, n);
    Eigen::VectorXd g(n);
    for (int i = 0; i < n; ++i) g(i) = eq.gradient[first + i];
    if (lambda > 0.0) H.diagonal() *= 1.0 + lambda;
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(H);
    if (ldlt.info() != Eigen::Success ||
        !(ldlt.vectorD().minCoeff() > 1e-12 * std::max(1.0, ldlt.vectorD().maxCoeff())))
        return false;
    const Eigen::VectorXd sub = ldlt.solve(-g);
    if (!sub.allFinite()) return false;
    x.setZero();
    x.segment(first, n) = sub;
    return true;
}

// Gauss-Newton on a robust (reweighted) cost with projective association converges linearly, not
// quadratically: the reweighting uses w(r) = rho'(r) / r where Newton would use rho''(r), which is
// smaller for Tukey's kernel, so each step is a roughly constant fraction q of the one before. The
// steps then form a geometric series, and the pose still has x q / (1 - q) to go after step x: a step
// that continues the one before it (q = x . x_prev / |x_prev|^2 in (0, 1)) is taken 1 / (1 - q) times
// as long, at most kMaxStretch (Aitken's extrapolation of a linearly converging sequence). A step that
// turns back (q <= 0) or grows (q >= 1) is taken as it is. The optimum is the same; fewer iterations
// reach it. Rotation and translation share the product (radians and metres: the scenes lie about a
// metre away).
class StepExtrapolation {
public:
    static constexpr double kMaxStretch = 3.0;

    // A new cost (another level, the kernel or colour joining): the earlier steps say nothing of it.
    void restart() { has_previous_ = false; }
    // The step to take for the Gauss-Newton step x.
    Vector6d stretch(const Vector6d& x) {
        Vector6d taken = x;
        if (has_previous_) {
            const double q = x.dot(previous_) / previous_.squaredNorm();
            if (q > 0.0 && q < 1.0) taken = x * std::min(kMaxStretch, 1.0 / (1.0 - q));
        }
        previous_ = x;
        has_previous_ = previous_.squaredNorm() > 0.0;
        return taken;
    }

private:
    Vector6d previous_ = Vector6d::Zero();
    bool has_previous_ = false;
};

// Smallest / largest eigenvalue of H after scaling it to a unit diagonal (D^-1/2 H D^-1/2), 0 for an
// empty or degenerate system. The scaling makes the ratio free of units (radians vs metres, depth vs
// intensity residuals): it measures how close some combination of motions comes to being
// unconstrained, not how large the residuals are.
inline float conditionRatio(const NormalEquations<double>& eq) {
    if (eq.count < 6) return 0.f;
    Matrix6d H = fullMatrix(eq);
    const Vector6d d = H.diagonal();
    if (!(d.minCoeff() > 0.0)) return 0.f;
    const Vector6d s = d.cwiseSqrt().cwiseInverse();
    H = s.asDiagonal() * H * s.asDiagonal();
    const Eigen::SelfAdjointEigenSolver<Matrix6d> solver(H, Eigen::EigenvaluesOnly);
    const Vector6d ev = solver.eigenvalues();  // ascending
    if (!(ev(5) > 0.0)) return 0.f;
    return float(std::max(0.0, ev(0)) / ev(5));
}

// How well point-to-plane terms pin the translation down, direction by direction: the eigenvalues of
// the translation block of their normal matrix (sum of w n n^T, the translation Jacobians being the
// model normals in camera coordinates) over its trace (sum of w). Free of units and of the number of
// terms: the share of the terms' weight along each direction, between 0 and 1/3 for the least
// constrained one (0 for a single plane, or a corridor seen without anything facing along it; 1/3
// when normals point evenly in all directions). Ascending, with the directions as columns.
struct TranslationConstraint {
    Eigen::Vector3d share = Eigen::Vector3d::Zero();
    Eigen::Matrix3d directions = Eigen::Matrix3d::Identity();
};
inline TranslationConstraint translationConstraint(const NormalEquations<double>& eq) {
    TranslationConstraint c;
    const Eigen::Matrix3d Htt = fullMatrix(eq).bottomRightCorner<3, 3>();
    const double trace = Htt.trace();
    if (eq.count < 6 || !(trace > 0.0)) return c;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(Htt);
    c.share = solver.eigenvalues().cwiseMax(0.0) / trace;
    c.directions = solver.eigenvectors();
    return c;
}

// The robust variance of a system's residuals: sum of w r^2 over the terms it took, per term. For
// residuals well inside the kernel's scale it is their variance; outliers count by the kernel's
// weight (Huber: linearly; Tukey: not at all), so a few do not inflate it.
inline double robustVariance(const NormalEquations<double>& eq) {
    return eq.count > 0 ? eq.weighted_cost / eq.count : 0.0;
}

// Inverse-variance weighting of two kinds of terms: the weight of a term of `b` against a term of `a`
// when each counts by the inverse of its own noise (maximum likelihood for Gaussian noise), the noise
// being each system's robust variance, but at least its floor (a system whose residuals vanish, e.g.
// a model seen in exactly the frame that built it, must not take all the weight). 0 when either has
// no terms.
inline double inverseVarianceWeight(const NormalEquations<double>& a, double a_floor, const NormalEquations<double>& b,
                                    double b_floor) {
    if (a.count == 0 || b.count == 0) return 0.0;
    return std::max(robustVariance(a), a_floor) / std::max(robustVariance(b), b_floor);
}

// The translation (metres) and rotation angle (degrees) between two poses.
inline void motionBetween(const Eigen::Matrix4d& a, const Eigen::Matrix4d& b, float& metres, float& degrees) {
    const Eigen::Matrix4d d = a.inverse() * b;
    metres = float(d.topRightCorner<3, 1>().norm());
    const double cos_angle = std::clamp((d.topLeftCorner<3, 3>().trace() - 1.0) / 2.0, -1.0, 1.0);
    degrees = float(std::acos(cos_angle) * 180.0 / EIGEN_PI);
}

}  // namespace voxfuse::pose
