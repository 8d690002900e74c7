// The relocaliser's rules on their own: how a frame's depth agrees with the model's, when a candidate
// is accepted, and when a frame the tracker did not fail is taken as lost.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "voxfuse/core/Error.h"
#include "voxfuse/engines/Relocaliser.h"
#include "voxfuse/shared/ColorTrackerTerms.h"  // intensityFromRgb

namespace voxfuse {
namespace {

TEST(RelocaliserTest, DepthAgreementCountsOverlapAndPixelsWithinTheTolerance) {
    Image<float> frame(Vec2i{10, 1}), model(Vec2i{10, 1});
    const float f[10] = {1.f, 1.f, 1.f, 1.f, 1.f, 1.f, 1.f, 1.f, 0.f, 0.f};          // 8 valid
    const float m[10] = {1.f, 1.01f, 1.019f, 1.03f, 0.9f, 1.f, 0.f, 0.f, 1.f, 0.f};  // 6 of them overlap
    for (int i = 0; i < 10; ++i) {
        frame.host()[i] = f[i];
        model.host()[i] = m[i];
    }
    const DepthAgreement a = compareDepth(frame, model, 0.02f);
    EXPECT_FLOAT_EQ(a.overlap, 6.f / 8.f);
    EXPECT_FLOAT_EQ(a.agreement, 4.f / 6.f) << "1, 1.01, 1.019 and 1 agree; 1.03 and 0.9 do not";
    Image<float> no_depth(Vec2i{10, 1});
    std::fill(no_depth.host(), no_depth.host() + no_depth.pixelCount(), 0.f);
    EXPECT_EQ(compareDepth(no_depth, model, 0.02f).overlap, 0.f) << "no valid depth: nothing overlaps";
    EXPECT_THROW(compareDepth(frame, Image<float>(Vec2i{5, 2}), 0.02f), ConfigError);
}

// A depth camera of 160x120 (16 x 12 cells of 10 pixels) whose colour camera is the same (registered
// frames), the frame's depth 1 m everywhere and its colours a pattern with no two rows alike.
View colorView(int rgb_scale = 1) {
    View view;
    view.calib.depth = Intrinsics{160, 120, 160.f, 160.f, 79.5f, 59.5f};
    view.calib.rgb = view.calib.depth;
    view.depth.resize(Vec2i{160, 120});
    std::fill(view.depth.host(), view.depth.host() + view.depth.pixelCount(), 1.f);
    view.rgb.resize(Vec2i{160 * rgb_scale, 120 * rgb_scale});
    for (int v = 0; v < view.rgb.height(); ++v)
        for (int u = 0; u < view.rgb.width(); ++u) {
            const int x = u / rgb_scale, y = v / rgb_scale;
            const unsigned char g = (unsigned char)((x * 37 + y * y * 11) % 200 + 20);
            view.rgb.at(u, v) = Vec4u8{g, g, g, 255};
        }
    return view;
}

// The model's colours: `grey(frame grey)` at each depth pixel.
template <class F>
Image<Vec4u8> modelColor(const View& registered, F grey) {
    Image<Vec4u8> color(registered.depth.size());
    for (int v = 0; v < color.height(); ++v)
        for (int u = 0; u < color.width(); ++u) {
            const unsigned char g = (unsigned char)grey(int(registered.rgb.at(u, v).x));
            color.at(u, v) = Vec4u8{g, g, g, 255};
        }
    return color;
}

// What RaycastEngine::renderIntensity gives for a map of these colours.
Image<float> intensities(const Image<Vec4u8>& color) {
    Image<float> grey(color.size());
    for (std::size_t i = 0; i < color.pixelCount(); ++i) grey.host()[i] = intensityFromRgb(color.host()[i]);
    return grey;
}

Image<float> constantDepth(float depth_m) {
    Image<float> depth(Vec2i{160, 120});
    std::fill(depth.host(), depth.host() + depth.pixelCount(), depth_m);
    return depth;
}

TEST(RelocaliserTest, ColorAgreementIsTheCorrelationOfIntensitiesWhereDepthsAgree) {
    const View view = colorView();
    Image<float> model_depth = constantDepth(1.005f);
    // Another exposure of the same surface: gain and offset do not count.
    ColorAgreement a =
        compareColor(view, model_depth, intensities(modelColor(view, [](int g) { return g / 2 + 30; })), 0.02f, 0.f);
    ASSERT_TRUE(a.compared);
    EXPECT_EQ(a.cells, 16 * 12);
    EXPECT_EQ(a.pixels, 160 * 120);
    EXPECT_GT(a.correlation, 0.99f);
    a = compareColor(view, model_depth, intensities(modelColor(view, [](int g) { return 250 - g; })), 0.02f, 0.f);
    ASSERT_TRUE(a.compared);
    EXPECT_LT(a.correlation, -0.99f) << "the negative";
    // Pixels whose depths disagree (an occluder) are not compared, whatever their colour.
    Image<Vec4u8> spoilt = modelColor(view, [](int g) { return g; });
    for (int v = 0; v < 120; ++v)
        for (int u = 0; u < 40; ++u) {
            model_depth.at(u, v) = 1.1f;
            spoilt.at(u, v) = Vec4u8{(unsigned char)(u * v % 7 * 30), 0, 255, 255};
        }
    a = compareColor(view, model_depth, intensities(spoilt), 0.02f, 0.f);
    ASSERT_TRUE(a.compared);
    EXPECT_EQ(a.pixels, 120 * 120);
    EXPECT_GT(a.correlation, 0.99f);
    // Colour at twice the calibrated resolution is the same camera, sampled at its pixels.
    a = compareColor(colorView(2), model_depth, intensities(spoilt), 0.02f, 0.f);
    ASSERT_TRUE(a.compared);
    EXPECT_GT(a.correlation, 0.99f);
}

TEST(RelocaliserTest, ColorFinerThanTheMapIsAveragedOverTheMapsFootprint) {
    // Colour at 4x the depth's resolution (fx 640): each depth pixel's 4x4 colour pixels hold the
    // map's colour plus texture finer than the map, +-60 grey levels in pairs that cancel. Voxels
    // of 1 / (1.5 * 160) m make the footprint at 1 m those 4x4 pixels.
    View view = colorView(4);
    Image<Vec4u8> map_color(view.depth.size());
    for (int y = 0; y < 120; ++y)
        for (int x = 0; x < 160; ++x) {
            const int g = (x * 37 + y * y * 11) % 120 + 68;
            map_color.at(x, y) = Vec4u8{(unsigned char)g, (unsigned char)g, (unsigned char)g, 255};
            for (int dy = 0; dy < 4; ++dy)
                for (int dx = 0; dx < 4; ++dx) {
                    // (dx, dy) and (3 - dx, 3 - dy) are a pair; the sign of each pair from a hash.
                    const bool first = dy < 2;
                    const int pair = first ? dx + 4 * dy : (3 - dx) + 4 * (3 - dy);
                    const unsigned hash =
                        (unsigned(x) * 73856093u) ^ (unsigned(y) * 19349663u) ^ (unsigned(pair) * 83492791u);
                    const int sign = (hash >> 4) & 1u ? 1 : -1;
                    const int fine = g + (first ? sign : -sign) * 60;
                    view.rgb.at(4 * x + dx, 4 * y + dy) =
                        Vec4u8{(unsigned char)fine, (unsigned char)fine, (unsigned char)fine, 255};
                }
        }
    const ColorAgreement points = compareColor(view, constantDepth(1.f), intensities(map_color), 0.02f, 0.f);
    ASSERT_TRUE(points.compared);
    EXPECT_LT(points.correlation, 0.7f)
        << "a colour pixel on its own carries the finer texture: the test shows something";
    const ColorAgreement footprint =
        compareColor(view, constantDepth(1.f), intensities(map_color), 0.02f, 1.f / (1.5f * 160.f));
    ASSERT_TRUE(footprint.compared);
    EXPECT_GT(footprint.correlation, 0.99f);
    EXPECT_EQ(footprint.pixels, 160 * 120);
}

TEST(RelocaliserTest, ColorIsSampledThroughTheDepthToColorExtrinsics) {
    // A colour camera 2.5 cm to the right of the depth camera (fx 160: 4 pixels at 1 m). It sees the
    // depth pixel u at its own u - 4; the model's colours sit at the depth pixels.
    View view = colorView();
    const Image<Vec4u8> at_depth_pixels = modelColor(view, [](int g) { return g; });
    view.calib.T_depth_rgb = Mat4f::identity();
    view.calib.T_depth_rgb.m[3] = 0.025f;  // rgb -> depth: x + 2.5 cm
    for (int v = 0; v < 120; ++v)
        for (int u = 0; u < 160; ++u)
            view.rgb.at(u, v) = u + 4 < 160 ? at_depth_pixels.at(u + 4, v) : Vec4u8{0, 0, 0, 255};
    ColorAgreement a = compareColor(view, constantDepth(1.f), intensities(at_depth_pixels), 0.02f, 0.f);
    ASSERT_TRUE(a.compared);
    EXPECT_GT(a.correlation, 0.99f);
    EXPECT_EQ(a.pixels, 156 * 120) << "the 4 right columns lie outside the colour image";
    view.calib.T_depth_rgb.m[3] = -0.025f;  // the extrinsics taken the wrong way round
    a = compareColor(view, constantDepth(1.f), intensities(at_depth_pixels), 0.02f, 0.f);
    ASSERT_TRUE(a.compared);
    EXPECT_LT(a.correlation, 0.5f);
}

TEST(RelocaliserTest, MapPixelsWithoutColorAreNotCompared) {
    // Voxels that never saw colour have no intensity (-1): half of each cell so, and the rest agreeing.
    const View view = colorView();
    Image<float> half = intensities(modelColor(view, [](int g) { return g; }));
    for (int v = 0; v < 120; ++v)
        for (int u = 0; u < 160; u += 2) half.at(u, v) = -1.f;
    const ColorAgreement a = compareColor(view, constantDepth(1.f), half, 0.02f, 0.f);
    ASSERT_TRUE(a.compared);
    EXPECT_EQ(a.pixels, 80 * 120);
    EXPECT_GT(a.correlation, 0.99f);
}

TEST(RelocaliserTest, ColorComparesTextureNotWhereBrightAndDarkRegionsLie) {
    // The same layout of a bright and a dark half, with unrelated texture in each: a place of the
    // same shape under other colours. The image-wide correlation would be high; the cells' is not.
    View view = colorView();
    Image<Vec4u8> other(view.depth.size());
    for (int v = 0; v < 120; ++v)
        for (int u = 0; u < 160; ++u) {
            const bool bright = u < 80;
            const int g = int(view.rgb.at(u, v).x) / 4 + (bright ? 180 : 20);
            view.rgb.at(u, v) = Vec4u8{(unsigned char)g, (unsigned char)g, (unsigned char)g, 255};
            const int h = (u * u * 13 + v * 29) % 50 + (bright ? 180 : 20);
            other.at(u, v) = Vec4u8{(unsigned char)h, (unsigned char)h, (unsigned char)h, 255};
        }
    const ColorAgreement a = compareColor(view, constantDepth(1.f), intensities(other), 0.02f, 0.f);
    ASSERT_TRUE(a.compared);
    EXPECT_LT(std::fabs(a.correlation), 0.3f);
}

TEST(RelocaliserTest, ColorGivesNoVerdictWithoutColorOrTexture) {
    const View view = colorView();
    const Image<float> model_depth = constantDepth(1.f);
    const Image<float> same = intensities(modelColor(view, [](int g) { return g; }));
    EXPECT_TRUE(compareColor(view, model_depth, same, 0.02f, 0.f).compared);
    EXPECT_FALSE(compareColor(view, model_depth, same, 0.02f, 0.f, 16 * 12 + 1).compared)
        << "fewer cells than asked for";
    const Image<float> plain = intensities(modelColor(view, [](int) { return 128; }));
    EXPECT_FALSE(compareColor(view, model_depth, plain, 0.02f, 0.f, 0).compared)
        << "no textured cell: no verdict, whatever the least asked for";
    EXPECT_FALSE(
        compareColor(view, model_depth, intensities(modelColor(view, [](int) { return 128; })), 0.02f, 0.f).compared)
        << "a plain surface correlates with nothing";
    View grey = colorView();
    grey.rgb = Image<Vec4u8>();
    EXPECT_FALSE(compareColor(grey, model_depth, same, 0.02f, 0.f).compared) << "a frame without colour";
    EXPECT_FALSE(compareColor(view, model_depth, Image<float>(), 0.02f, 0.f).compared) << "a map without colour";
    EXPECT_THROW(compareColor(view, model_depth, Image<float>(Vec2i{20, 15}), 0.02f, 0.f), ConfigError);
}

RelocalisationCheck passingCheck() {
    RelocalisationCheck c;
    c.refined.quality = TrackingQuality::Good;
    c.refined.inlier_ratio = 0.7f;
    c.refined.residual_m = 0.003f;
    c.depth = {0.95f, 0.9f};
    c.step_m = 0.001f;
    c.step_deg = 0.1f;
    return c;
}

TEST(RelocaliserTest, ACandidateIsTakenOnlyWhenEveryMeasurePasses) {
    const RelocalisationSettings s;
    EXPECT_TRUE(acceptRelocalisation(s, passingCheck()));
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const std::vector<std::pair<const char*, void (*)(RelocalisationCheck&)>> spoilers = {
        {"poor", [](RelocalisationCheck& c) { c.refined.quality = TrackingQuality::Poor; }},
        {"few inliers", [](RelocalisationCheck& c) { c.refined.inlier_ratio = 0.45f; }},
        {"large residual", [](RelocalisationCheck& c) { c.refined.residual_m = 0.008f; }},
        {"little overlap", [](RelocalisationCheck& c) { c.depth.overlap = 0.4f; }},
        {"disagreement", [](RelocalisationCheck& c) { c.depth.agreement = 0.64f; }},
        {"not converged", [](RelocalisationCheck& c) { c.step_m = 0.02f; }},
        {"still turning", [](RelocalisationCheck& c) { c.step_deg = 2.f; }},
        {"NaN residual",
         [](RelocalisationCheck& c) { c.refined.residual_m = std::numeric_limits<float>::quiet_NaN(); }},
        {"other colours",
         [](RelocalisationCheck& c) {
             c.color = ColorAgreement{true, 0.3f, 40, 5000};
         }},
        {"NaN colour",
         [](RelocalisationCheck& c) {
             c.color = ColorAgreement{true, std::numeric_limits<float>::quiet_NaN(), 40, 5000};
         }},
    };
    for (const auto& [what, spoil] : spoilers) {
        RelocalisationCheck c = passingCheck();
        spoil(c);
        EXPECT_FALSE(acceptRelocalisation(s, c)) << what;
    }
    RelocalisationCheck c = passingCheck();
    c.depth.agreement = nan;
    EXPECT_FALSE(acceptRelocalisation(s, c));
    c = passingCheck();
    c.color = ColorAgreement{false, -1.f, 1, 10};
    EXPECT_TRUE(acceptRelocalisation(s, c)) << "colours not compared: no colour test";
    c.color = ColorAgreement{true, 0.8f, 40, 5000};
    EXPECT_TRUE(acceptRelocalisation(s, c));
}

TrackingState withInliers(float ratio) {
    TrackingState t;
    t.inlier_ratio = ratio;
    return t;
}

TEST(RelocaliserTest, AnInlierRatioCollapseAfterGoodFramesLooksLost) {
    Relocaliser r(RelocalisationSettings{}, {640, 480});
    EXPECT_FALSE(r.looksLost(withInliers(0.1f))) << "no good frames yet: nothing to compare with";
    for (float ratio : {0.80f, 0.78f, 0.76f, 0.79f, 0.30f}) r.rememberGoodFrame(withInliers(ratio));
    EXPECT_TRUE(r.looksLost(withInliers(0.35f))) << "under half the median (0.78)";
    EXPECT_FALSE(r.looksLost(withInliers(0.40f)));
    EXPECT_TRUE(r.looksLost(withInliers(std::numeric_limits<float>::quiet_NaN())));
    r.forgetRecentFrames();
    EXPECT_FALSE(r.looksLost(withInliers(0.1f)));
    // Only the last recent_frames count: a scene that slowly shows less of the map is not a loss.
    for (int i = 0; i < 10; ++i) r.rememberGoodFrame(withInliers(0.8f));
    for (int i = 0; i < 10; ++i) r.rememberGoodFrame(withInliers(0.4f));
    EXPECT_FALSE(r.looksLost(withInliers(0.3f)));
}

TEST(RelocaliserTest, TimeBetweenFramesComesFromTimestampsElseFromIndicesAt30Hz) {
    EXPECT_DOUBLE_EQ(secondsBetween({100.0, 7}, {101.5, 8}), 1.5);  // a cut: the timestamps know, the indices do not
    EXPECT_DOUBLE_EQ(secondsBetween({0.0, 10}, {0.0, 40}), 1.0);
    EXPECT_DOUBLE_EQ(secondsBetween({100.0, 10}, {0.0, 40}), 1.0);  // only one timestamp: the indices
    EXPECT_EQ(secondsBetween({}, {101.0, 3}), -1.0);                // no earlier frame
    EXPECT_EQ(secondsBetween({101.0, 5}, {100.0, 6}), -1.0);        // not later: unknown
    EXPECT_EQ(secondsBetween({0.0, 6}, {0.0, 6}), -1.0);
}

TEST(RelocaliserTest, AKeyframeTheCameraCouldNotHaveReachedIsNoCandidate) {
    RelocalisationSettings s;  // 9 m/s
    const Mat4f last = Mat4f::identity();
    Mat4f candidate = Mat4f::identity();
    candidate.m[3] = 3.f;
    candidate.m[11] = 4.f;                               // 5 m away
    EXPECT_FALSE(withinReach(s, last, candidate, 0.5));  // 4.5 m in half a second
    EXPECT_TRUE(withinReach(s, last, candidate, 0.6));   // 5.4 m
    EXPECT_TRUE(withinReach(s, last, last, 0.0001));
    EXPECT_TRUE(withinReach(s, last, candidate, -1.0));  // time unknown: no limit
    s.max_speed_m_per_s = 0.f;                           // no limit
    EXPECT_TRUE(withinReach(s, last, candidate, 0.01));
}

TEST(RelocaliserTest, RejectsSettingsItCannotUse) {
    RelocalisationSettings s;
    s.candidates = 0;
    EXPECT_THROW(Relocaliser(s, {640, 480}), ConfigError);
    s = RelocalisationSettings();
    s.keyframe_min_dissimilarity = 1.5f;
    EXPECT_THROW(Relocaliser(s, {640, 480}), ConfigError);
    s = RelocalisationSettings();
    s.max_keyframes = 0;
    EXPECT_THROW(Relocaliser(s, {640, 480}), ConfigError);
    s = RelocalisationSettings();
    s.ferns.tests_per_fern = 0;
    EXPECT_THROW(Relocaliser(s, {640, 480}), ConfigError) << "checked when made, not at the first frame";
    for (float correlation : {-1.5f, 1.1f, std::numeric_limits<float>::quiet_NaN()}) {
        s = RelocalisationSettings();
        s.min_color_correlation = correlation;
        EXPECT_THROW(Relocaliser(s, {640, 480}), ConfigError) << correlation;
    }
    for (float speed : {-1.f, std::numeric_limits<float>::quiet_NaN()}) {
        s = RelocalisationSettings();
        s.max_speed_m_per_s = speed;
        EXPECT_THROW(Relocaliser(s, {640, 480}), ConfigError) << speed;
    }
}

}  // namespace
}  // namespace voxfuse
