// The trackers' host algebra on systems built by hand: how much of the terms' weight constrains each
// translation direction, the stretching of linearly converging steps, and the weight that balances
// two kinds of terms by their noise.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "engines/PoseUpdate.h"
#include "voxfuse/shared/RobustKernel.h"

namespace voxfuse {
namespace {

// Point-to-plane terms of points p with model normals n (camera coordinates) and residuals r.
struct Terms {
    NormalEquations<double> eq = NormalEquations<double>::zero();
    void add(const Eigen::Vector3f& p, const Eigen::Vector3f& n, float r) {
        const Eigen::Vector3f pxn = p.cross(n);
        const float J[6] = {pxn.x(), pxn.y(), pxn.z(), n.x(), n.y(), n.z()};
        eq.addTerm(J, r, 1.f);
    }
};

// A corridor seen along z: floor and ceiling (normals +-y), two walls (normals +-x), nothing facing z.
Terms corridorTerms(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1.f, 1.f), depth(1.f, 4.f), r(-0.01f, 0.01f);
    Terms t;
    for (int i = 0; i < 400; ++i) {
        const float z = depth(rng);
        t.add({u(rng), 1.2f, z}, {0.f, -1.f, 0.f}, r(rng));
        t.add({u(rng), -1.3f, z}, {0.f, 1.f, 0.f}, r(rng));
        t.add({1.f, u(rng), z}, {-1.f, 0.f, 0.f}, r(rng));
        t.add({-1.f, u(rng), z}, {1.f, 0.f, 0.f}, r(rng));
    }
    return t;
}

TEST(PoseUpdateTest, TheTranslationConstraintIsTheShareOfTheNormalsAlongEachDirection) {
    std::mt19937 rng(3);
    // Normals along the three axes, in proportions 1 : 2 : 7 of the weight.
    Terms t;
    for (int i = 0; i < 10; ++i)
        t.add({0.1f * i, 0.2f, 2.f},
              i < 1   ? Eigen::Vector3f::UnitX()
              : i < 3 ? Eigen::Vector3f::UnitY()
                      : Eigen::Vector3f::UnitZ(),
              0.f);
    const pose::TranslationConstraint c = pose::translationConstraint(t.eq);
    EXPECT_NEAR(c.share(0), 0.1, 1e-9);
    EXPECT_NEAR(c.share(1), 0.2, 1e-9);
    EXPECT_NEAR(c.share(2), 0.7, 1e-9);
    EXPECT_NEAR(std::abs(c.directions.col(0).x()), 1.0, 1e-9) << "the least constrained direction is x";

    const pose::TranslationConstraint corridor = pose::translationConstraint(corridorTerms(rng).eq);
    EXPECT_LT(corridor.share(0), 1e-12) << "nothing faces along the corridor";
    EXPECT_NEAR(std::abs(corridor.directions.col(0).z()), 1.0, 1e-9);
    EXPECT_NEAR(corridor.share(1), 0.5, 1e-9);
    EXPECT_EQ(pose::translationConstraint(NormalEquations<double>::zero()).share(0), 0.0)
        << "no terms: nothing constrained";
}

// A fixed-point iteration that converges linearly, as reweighted Gauss-Newton does: each step covers
// half of what is left to a target. Alone it needs 14 steps to come within 1e-4 of it; stretched, the
// second step lands on it (the series x + x/2 + x/4 + ... sums to 2x) and the third is nothing.
TEST(PoseUpdateTest, StretchedStepsOfAGeometricSeriesReachItsLimit) {
    const pose::Vector6d target = (pose::Vector6d() << 0.01, -0.02, 0.005, 0.03, 0.01, -0.04).finished();
    auto stepsToTarget = [&](bool stretched) {
        pose::StepExtrapolation extrapolation;
        pose::Vector6d x = pose::Vector6d::Zero();
        for (int step = 1; step <= 100; ++step) {
            const pose::Vector6d gauss_newton = 0.5 * (target - x);
            x += stretched ? extrapolation.stretch(gauss_newton) : gauss_newton;
            if ((target - x).norm() < 1e-4 * target.norm()) return step;
        }
        return 101;
    };
    EXPECT_EQ(stepsToTarget(false), 14);
    EXPECT_EQ(stepsToTarget(true), 2);
}

TEST(PoseUpdateTest, OnlyAStepThatContinuesAShrinkingSeriesIsStretched) {
    const pose::Vector6d x = (pose::Vector6d() << 0.001, 0.0, -0.002, 0.0005, 0.001, 0.0).finished();
    pose::StepExtrapolation e;
    EXPECT_EQ(e.stretch(x), x) << "the first step has nothing to continue";
    EXPECT_TRUE(e.stretch(0.25 * x).isApprox(x / 3.0, 1e-12)) << "q = 1/4: taken 4/3 times as long";
    EXPECT_TRUE(e.stretch(0.2 * x).isApprox(0.2 * x * 3.0, 1e-12)) << "q = 0.8 would be 5x: at most kMaxStretch";
    EXPECT_EQ(e.stretch(-0.1 * x), -0.1 * x) << "a step that turns back overshot: taken as it is";
    EXPECT_EQ(e.stretch(-0.2 * x), -0.2 * x) << "q = 2: a growing step is taken as it is";
    e.restart();
    EXPECT_EQ(e.stretch(-0.1 * x), -0.1 * x) << "after a restart (a new cost) nothing is continued";
    const pose::Vector6d across = (pose::Vector6d() << 0.0, 0.001, 0.0, 0.0, 0.0, 0.003).finished();
    ASSERT_NEAR(across.dot(-0.1 * x), 0.0, 1e-15);
    EXPECT_EQ(e.stretch(across), across) << "a step at right angles continues nothing";
}

// Depth residuals of +-2 mm and colour residuals of +-0.05 (within their kernels' scales: weight 1):
// a colour term weighs (2e-3)^2 / 0.05^2 = 1.6e-3 of a depth term. Colour residuals at half the
// brightness weigh four times as much; the floors hold for residuals that vanish.
TEST(PoseUpdateTest, InverseVarianceWeightIsTheRatioOfTheResidualsRobustVariances) {
    auto system = [](double residual, RobustKernel kernel, double scale, int n) {
        NormalEquations<double> eq = NormalEquations<double>::zero();
        const float J[6] = {1.f, 0.f, 0.f, 0.f, 0.f, 0.f};
        for (int i = 0; i < n; ++i) {
            const float r = float(i % 2 ? residual : -residual);
            eq.addTerm(J, r, robustWeight(kernel, r, float(scale)));
        }
        return eq;
    };
    const auto depth = system(2e-3, RobustKernel::Tukey, 1.0, 100), color = system(0.05, RobustKernel::Huber, 0.1, 300);
    const double floor_d = 1e-8, floor_i = 1e-5;
    EXPECT_NEAR(pose::robustVariance(color), 0.05 * 0.05, 1e-9);
    EXPECT_NEAR(pose::robustVariance(depth), 4e-6 * (1 - 4e-6) * (1 - 4e-6), 1e-12)
        << "Tukey at a 1 m scale weighs 2 mm by (1 - 4e-6)^2";
    EXPECT_NEAR(pose::inverseVarianceWeight(depth, floor_d, color, floor_i), 4e-6 / 2.5e-3, 1e-7);
    const auto dim = system(0.025, RobustKernel::Huber, 0.1, 300);
    EXPECT_NEAR(pose::inverseVarianceWeight(depth, floor_d, dim, floor_i),
                4 * pose::inverseVarianceWeight(depth, floor_d, color, floor_i), 1e-7);
    const auto huge = system(1.0, RobustKernel::Huber, 0.1, 300);
    EXPECT_NEAR(pose::robustVariance(huge), 0.1, 1e-7)
        << "an outlier counts by the kernel's weight (Huber: scale / |r|)";
    EXPECT_NEAR(pose::inverseVarianceWeight(system(0.0, RobustKernel::Tukey, 1.0, 10), floor_d,
                                            system(0.0, RobustKernel::Huber, 0.1, 10), floor_i),
                floor_d / floor_i, 1e-12)
        << "residuals that vanish count as the floors";
    EXPECT_EQ(pose::inverseVarianceWeight(depth, floor_d, NormalEquations<double>::zero(), floor_i), 0.0)
        << "no colour terms";
}

}  // namespace
}  // namespace voxfuse
