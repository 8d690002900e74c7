// The inline maths of core/Math.h that stand in for library calls, against the library.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/Voxel.h"

namespace voxfuse {
namespace {

TEST(MathTest, ExpOfNegativeFollowsTheLibraryToFloatPrecision) {
    // The fit's error (8e-8), plus that of y = x log2 e rounded to float, which grows with x: within
    // 3e-7 x of the exact value (a few float ulps per unit of x).
    double worst = 0.0;
    for (int i = 0; i < 870000; ++i) {
        const float x = float(i) * 1e-4f;
        const double exact = std::exp(-double(x));
        worst = std::max(worst, std::fabs(double(expOfNegative(x)) - exact) / exact / std::max(1.0, double(x)));
    }
    EXPECT_LT(worst, 3e-7) << "largest relative error over [0, 87), per unit of x beyond 1";
    EXPECT_EQ(expOfNegative(0.f), std::exp(-0.f) * 0.99999994f) << "the fit's value at 0";
    EXPECT_EQ(expOfNegative(87.f), 0.f);
    EXPECT_EQ(expOfNegative(1e30f), 0.f);
    EXPECT_EQ(expOfNegative(std::numeric_limits<float>::infinity()), 0.f);
    EXPECT_EQ(expOfNegative(std::numeric_limits<float>::quiet_NaN()), 0.f) << "no NaN weight";
    EXPECT_FLOAT_EQ(expOfNegative(-1.f), 1.f) << "negative arguments are taken as 0";
}

TEST(MathTest, FloatFromBitsIsTheFloatOfThoseBits) {
    EXPECT_EQ(floatFromBits(0x3f800000u), 1.f);
    EXPECT_EQ(floatFromBits(0x40000000u), 2.f);
    EXPECT_EQ(floatFromBits(std::uint32_t(127 - 125) << 23), std::ldexp(1.f, -125));
}

TEST(MathTest, QuantisedSdfIsRintOfTheScaledValue) {
    // Every float the scaled value can take near the integers and their halves, and a dense sweep.
    for (int k = -32767; k <= 32767; ++k)
        for (const float offset : {-0.5f, 0.f, 0.5f})
            for (float v = float(k) + offset, n = 0; n < 3; ++n, v = std::nextafter(v, 1e9f)) {
                const float f = v / 32767.f;
                EXPECT_EQ(quantiseSdf(f), std::int16_t(std::rint(f * 32767.f))) << f;
            }
    for (int i = -1000000; i <= 1000000; ++i) {
        const float f = float(i) * 1e-6f;
        ASSERT_EQ(quantiseSdf(f), std::int16_t(std::rint(f * 32767.f))) << f;
    }
    EXPECT_EQ(quantiseSdf(1.f), 32767);
    EXPECT_EQ(quantiseSdf(-1.f), -32767);
}

}  // namespace
}  // namespace voxfuse
