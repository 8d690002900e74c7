// Fern codes of exact synthetic views: the same view gives the same code, nearby views share most
// codes, unrelated ones few, and the small images the tests read are what they claim.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "DeviceTestSupport.h"
#include "SyntheticViews.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/FernEncoder.h"

namespace voxfuse {
namespace {

const Intrinsics kCamera = test::kinectIntrinsics(160, 120);
const Eigen::Vector3f kTarget{0.1f, 0.05f, 0.6f};  // the room's objects

// The room seen from `degrees` along a circle of radius 1.6 m around its objects, at head height.
View roomView(float degrees, float radius_m = 1.6f) {
    static const synth::SyntheticScene room = synth::SyntheticScene::defaultRoom();
    const float a = degrees * float(EIGEN_PI) / 180.f;
    const Eigen::Vector3f eye = kTarget + Eigen::Vector3f(radius_m * std::cos(a), radius_m * std::sin(a), 0.85f);
    return test::renderView(room, kCamera, test::lookAt(eye, kTarget));
}

FernCode encode(const View& view, FernSettings settings = {}) {
    return FernEncoder(settings, view.depth.size(), true).encode(view.depth, view.rgb);
}

TEST(FernEncoderTest, TheSameSettingsGiveTheSameCode) {
    const View view = roomView(180.f);
    const FernCode code = encode(view);
    ASSERT_EQ(code.size(), 500u);
    EXPECT_EQ(encode(view), code);
    for (const std::uint8_t word : code) EXPECT_LT(word, 16) << "four tests per fern: four bits";
    FernSettings other;
    other.seed = 2;
    EXPECT_GT(fernDissimilarity(encode(view, other), code), 0.3f) << "another seed draws other tests";
}

TEST(FernEncoderTest, NearbyViewsShareMostCodesAndDistantViewsFew) {
    const FernCode here = encode(roomView(180.f));
    const float near = fernDissimilarity(here, encode(roomView(181.f)));
    const float apart = fernDissimilarity(here, encode(roomView(200.f)));
    const float opposite = fernDissimilarity(here, encode(roomView(0.f)));
    std::printf("[ ferns    ] dissimilarity 1 degree on %.3f, 20 degrees %.3f, the other side %.3f\n", near, apart,
                opposite);
    EXPECT_LT(near, 0.15f);
    EXPECT_GT(apart, 0.3f);
    EXPECT_GT(opposite, 0.5f);
    EXPECT_LT(near, apart);
}

TEST(FernEncoderTest, IntensityIsNormalisedSoExposureMovesFewBits) {
    View view = roomView(180.f);
    const FernCode bright = encode(view);
    for (std::size_t i = 0; i < view.rgb.pixelCount(); ++i) {
        Vec4u8& p = view.rgb.host()[i];
        p = Vec4u8{(unsigned char)(0.6f * p.x), (unsigned char)(0.6f * p.y), (unsigned char)(0.6f * p.z), 255};
    }
    EXPECT_LT(fernDissimilarity(bright, encode(view)), 0.05f);
    // Without colour the tests read depth only, and intensity makes a difference to the code.
    const FernCode depth_only = FernEncoder(FernSettings{}, view.depth.size(), false).encode(view.depth, view.rgb);
    EXPECT_GT(fernDissimilarity(bright, depth_only), 0.2f);
}

// The small images are averaged where the frames are (the low-level engine's cell averages): these
// closed-form and written-out cases run on every device.
class FernEncoderDeviceTest : public ::testing::TestWithParam<Device> {
protected:
    void SetUp() override { VF_SKIP_IF_UNAVAILABLE(GetParam()); }
};

TEST_P(FernEncoderDeviceTest, SmallImagesAverageValidDepthAndNormaliseIntensity) {
    Image<float> depth(Vec2i{160, 120});
    Image<Vec4u8> rgb(Vec2i{160, 120});
    for (int y = 0; y < 120; ++y)
        for (int x = 0; x < 160; ++x) {
            depth.at(x, y) = x < 80 ? 0.f : (x % 2 ? 1.f : 3.f);  // left half: no measurement
            const unsigned char v = (unsigned char)(y < 60 ? 50 : 150);
            rgb.at(x, y) = Vec4u8{v, v, v, 255};
        }
    FernEncoder encoder(FernSettings{}, depth.size(), true, GetParam());
    ASSERT_EQ(encoder.codeImageSize(), (Vec2i{80, 60}));
    std::vector<float> d, intensity;
    encoder.shrink(depth, rgb, d, intensity);
    ASSERT_EQ(d.size(), 80u * 60u);
    EXPECT_EQ(d[10 + 30 * 80], 0.f) << "no valid pixel near: no depth";
    EXPECT_FLOAT_EQ(d[60 + 30 * 80], 2.f) << "the average of 1 m and 3 m";
    EXPECT_FLOAT_EQ(d[40 + 30 * 80], 2.f) << "next to the hole, valid cells alone count";
    double mean = 0, square = 0;
    for (const float v : intensity) mean += v;
    mean /= double(intensity.size());
    for (const float v : intensity) square += (v - mean) * (v - mean);
    EXPECT_NEAR(mean, 0.0, 1e-4);
    EXPECT_NEAR(std::sqrt(square / double(intensity.size())), 1.0, 1e-3);
    EXPECT_LT(intensity[0], 0.f);
    EXPECT_GT(intensity[80 * 59], 0.f);
}

// A frame whose size is no multiple of the code image's (cells of 2 and 3 pixels), with holes, against
// the definition written out pixel by pixel: each pixel adds to the cell (x * w / W, y * h / H), then
// the 1-2-1 smoothing weighted by the cells' counts.
TEST_P(FernEncoderDeviceTest, SmallDepthIsTheCellAverageOfValidPixelsSmoothed) {
    const Vec2i frame{203, 151};
    Image<float> depth(frame);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (int y = 0; y < frame.y; ++y)
        for (int x = 0; x < frame.x; ++x) depth.at(x, y) = u(rng) < 0.3f ? 0.f : 0.5f + 2.f * u(rng);
    FernEncoder encoder(FernSettings{}, frame, false, GetParam());
    const Vec2i small = encoder.codeImageSize();
    ASSERT_EQ(small, (Vec2i{80, 60}));
    std::vector<double> sum(std::size_t(small.x * small.y), 0.0), count(sum.size(), 0.0);
    for (int y = 0; y < frame.y; ++y)
        for (int x = 0; x < frame.x; ++x)
            if (depth.at(x, y) > 0.f) {
                const std::size_t c = std::size_t(x * small.x / frame.x + (y * small.y / frame.y) * small.x);
                sum[c] += depth.at(x, y);
                count[c] += 1.0;
            }
    std::vector<float> d, intensity;
    encoder.shrink(depth, Image<Vec4u8>(), d, intensity);
    ASSERT_EQ(d.size(), sum.size());
    const double kernel[3] = {1.0, 2.0, 1.0};
    for (int cy = 0; cy < small.y; ++cy)
        for (int cx = 0; cx < small.x; ++cx) {
            double s = 0.0, w = 0.0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int x = cx + dx, y = cy + dy;
                    if (x < 0 || y < 0 || x >= small.x || y >= small.y) continue;
                    const std::size_t c = std::size_t(x + y * small.x);
                    if (count[c] == 0.0) continue;
                    s += kernel[dx + 1] * kernel[dy + 1] * sum[c];  // weight x count x mean
                    w += kernel[dx + 1] * kernel[dy + 1] * count[c];
                }
            EXPECT_NEAR(d[std::size_t(cx + cy * small.x)], w > 0.0 ? s / w : 0.0, 1e-5) << "cell " << cx << ", " << cy;
        }
}

TEST(FernEncoderTest, RejectsSettingsItCannotUse) {
    FernSettings s;
    s.tests_per_fern = 9;
    EXPECT_THROW(FernEncoder(s, {640, 480}, true), ConfigError);
    s = FernSettings();
    s.fern_count = 0;
    EXPECT_THROW(FernEncoder(s, {640, 480}, true), ConfigError);
    EXPECT_THROW(FernEncoder(FernSettings{}, {0, 30}, true), ConfigError);
    EXPECT_EQ(FernEncoder(FernSettings{}, {40, 30}, true).codeImageSize(), (Vec2i{40, 30}))
        << "a frame smaller than the code image";
    FernEncoder encoder(FernSettings{}, {160, 120}, true);
    EXPECT_THROW(encoder.encode(Image<float>(Vec2i{320, 240}), Image<Vec4u8>()), ConfigError);
    EXPECT_EQ(fernDissimilarity(FernCode(500, 0), FernCode(400, 0)), 1.f);
}

INSTANTIATE_TEST_SUITE_P(Devices, FernEncoderDeviceTest, test::kAllDevices, test::DeviceName());

}  // namespace
}  // namespace voxfuse
