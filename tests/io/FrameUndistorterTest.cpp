#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>
#include <vector>

#include "IoTestUtil.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/FrameUndistorter.h"

namespace voxfuse {
namespace {

const Intrinsics kCamera{320, 240, 250.f, 250.f, 159.5f, 119.5f};
// Barrel distortion of a wide lens, with some decentring: up to ~20 px displacement at the corners.
const LensDistortion kLens{-0.28f, 0.09f, 0.0012f, -0.0009f, 0.f};

// The Brown-Conrady model (as OpenCV): where a point seen at `ideal` by a perfect pinhole camera
// appears in the raw image of the distorting lens.
Vec2f distortPixel(const Intrinsics& k, const LensDistortion& d, Vec2f ideal) {
    const double x = (ideal.x - k.cx) / k.fx, y = (ideal.y - k.cy) / k.fy;
    const double r2 = x * x + y * y;
    const double radial = 1.0 + d.k1 * r2 + d.k2 * r2 * r2 + d.k3 * r2 * r2 * r2;
    const double xd = x * radial + 2.0 * d.p1 * x * y + d.p2 * (r2 + 2.0 * x * x);
    const double yd = y * radial + d.p1 * (r2 + 2.0 * y * y) + 2.0 * d.p2 * x * y;
    return {float(k.fx * xd + k.cx), float(k.fy * yd + k.cy)};
}

RGBDCalib calibWithLens() {
    RGBDCalib calib;
    calib.rgb = kCamera;
    calib.depth = kCamera;
    calib.rgb_distortion = kLens;
    calib.depth_distortion = kLens;
    return calib;
}

// A raw colour image holding small Gaussian spots, one at the distorted position of each ideal point.
Image<Vec4u8> rawImageOfSpots(const std::vector<Vec2f>& ideal_points) {
    std::vector<Vec2f> raw;
    for (Vec2f p : ideal_points) raw.push_back(distortPixel(kCamera, kLens, p));
    Image<Vec4u8> image(kCamera.size());
    for (int y = 0; y < kCamera.height; ++y)
        for (int x = 0; x < kCamera.width; ++x) {
            double value = 0.0;
            for (Vec2f c : raw) {
                const double d2 = (x - c.x) * (x - c.x) + (y - c.y) * (y - c.y);
                value += 255.0 * std::exp(-d2 / (2.0 * 1.2 * 1.2));
            }
            const auto v = std::uint8_t(std::min(255.0, value));
            image.at(x, y) = Vec4u8{v, v, v, 255};
        }
    return image;
}

// Intensity-weighted centre of the spot near `guess`.
Vec2f spotCentre(const Image<Vec4u8>& image, Vec2f guess) {
    double sum = 0.0, sx = 0.0, sy = 0.0;
    const int gx = int(std::lround(guess.x)), gy = int(std::lround(guess.y));
    for (int y = gy - 6; y <= gy + 6; ++y)
        for (int x = gx - 6; x <= gx + 6; ++x) {
            if (x < 0 || y < 0 || x >= image.width() || y >= image.height()) continue;
            const double w = std::max(0.0, double(image.at(x, y).x) - 8.0);
            sum += w;
            sx += w * x;
            sy += w * y;
        }
    return sum > 0.0 ? Vec2f{float(sx / sum), float(sy / sum)} : Vec2f{-1000.f, -1000.f};
}

// Distance of p from the line through a and b.
double distanceToLine(Vec2f p, Vec2f a, Vec2f b) {
    const double dx = b.x - a.x, dy = b.y - a.y;
    return std::abs(dy * (p.x - a.x) - dx * (p.y - a.y)) / std::hypot(dx, dy);
}

RGBDFrame frameWith(Image<Vec4u8> rgb, Image<std::uint16_t> depth) {
    RGBDFrame frame;
    frame.index = 4;
    frame.depth_path = "depth/0004.png";
    frame.rgb = std::move(rgb);
    frame.depth_raw = std::move(depth);
    return frame;
}

TEST(FrameUndistorter, AKnownPointMapsBackToItsIdealPosition) {
    const std::vector<Vec2f> ideal = {{159.5f, 119.5f}, {40.f, 30.f}, {285.f, 205.f}, {60.f, 200.f}, {250.f, 50.f}};
    const FrameUndistorter undistorter(calibWithLens());
    ASSERT_TRUE(undistorter.active());
    RGBDFrame frame = frameWith(rawImageOfSpots(ideal), Image<std::uint16_t>());

    // In the raw image the off-centre spots are far from their ideal positions...
    const Vec2f raw_spot = spotCentre(frame.rgb, distortPixel(kCamera, kLens, ideal[1]));
    EXPECT_GT(std::hypot(raw_spot.x - ideal[1].x, raw_spot.y - ideal[1].y), 5.0);
    undistorter.apply(frame);
    // ...and after undistortion each is where the pinhole camera sees it.
    for (Vec2f p : ideal) {
        const Vec2f c = spotCentre(frame.rgb, p);
        EXPECT_NEAR(c.x, p.x, 0.35) << "ideal (" << p.x << ", " << p.y << ")";
        EXPECT_NEAR(c.y, p.y, 0.35) << "ideal (" << p.x << ", " << p.y << ")";
    }
}

TEST(FrameUndistorter, AStraightLineIsStraightAgain) {
    const Vec2f a{20.f, 45.f}, b{300.f, 25.f};  // across the top of the image, where the lens bends most
    std::vector<Vec2f> ideal;
    for (int i = 0; i <= 8; ++i) ideal.push_back(Vec2f{a.x + (b.x - a.x) * i / 8.f, a.y + (b.y - a.y) * i / 8.f});
    RGBDFrame frame = frameWith(rawImageOfSpots(ideal), Image<std::uint16_t>());

    // The lens bends the line: the raw spots leave the chord through the raw end points.
    const Vec2f raw_a = distortPixel(kCamera, kLens, a), raw_b = distortPixel(kCamera, kLens, b);
    double worst_raw = 0.0;
    for (Vec2f p : ideal)
        worst_raw = std::max(worst_raw, distanceToLine(distortPixel(kCamera, kLens, p), raw_a, raw_b));
    EXPECT_GT(worst_raw, 2.0);

    FrameUndistorter(calibWithLens()).apply(frame);
    for (Vec2f p : ideal) EXPECT_LT(distanceToLine(spotCentre(frame.rgb, p), a, b), 0.35);
}

TEST(FrameUndistorter, DepthIsResampledNearestNeighbourSoNoValueIsInvented) {
    Image<std::uint16_t> depth(kCamera.size());
    const Vec2f ideal{70.f, 60.f};
    const Vec2f raw = distortPixel(kCamera, kLens, ideal);
    for (int y = 0; y < kCamera.height; ++y)
        for (int x = 0; x < kCamera.width; ++x) {
            std::uint16_t v = x < kCamera.width / 2 ? 1000 : 3000;
            if (x % 37 == 0) v = 0;  // invalid columns
            if (std::abs(x - raw.x) <= 1.5f && std::abs(y - raw.y) <= 1.5f) v = 2000;
            depth.at(x, y) = v;
        }
    RGBDFrame frame = frameWith(Image<Vec4u8>(), std::move(depth));
    FrameUndistorter(calibWithLens()).apply(frame);
    for (std::size_t i = 0; i < frame.depth_raw.pixelCount(); ++i) {
        const std::uint16_t v = frame.depth_raw.host()[i];
        ASSERT_TRUE(v == 0 || v == 1000 || v == 2000 || v == 3000) << "pixel " << i << " = " << v;
    }
    EXPECT_EQ(frame.depth_raw.at(70, 60), 2000);  // the patch moved to where the pinhole camera sees it
}

// A sequence undistorted through one scratch alternates between two sets of image memory (the
// frame's and the scratch's) and gives what the scratch-free call gives.
TEST(FrameUndistorter, UndistortingThroughAScratchAllocatesNoImagesAfterTheFirstFrame) {
    const FrameUndistorter undistorter(calibWithLens());
    Image<std::uint16_t> raw_depth(kCamera.size());
    for (std::size_t i = 0; i < raw_depth.pixelCount(); ++i) raw_depth.host()[i] = std::uint16_t(1000 + i % 2000);
    const Image<Vec4u8> raw_rgb = rawImageOfSpots({{40.f, 30.f}, {250.f, 50.f}});
    auto copyOf = [](const auto& image) {
        std::remove_cv_t<std::remove_reference_t<decltype(image)>> copy(image.size());
        std::copy(image.host(), image.host() + image.pixelCount(), copy.host());
        return copy;
    };
    RGBDFrame expected = frameWith(copyOf(raw_rgb), copyOf(raw_depth));
    undistorter.apply(expected);

    RGBDFrame frame = frameWith(Image<Vec4u8>(kCamera.size()), Image<std::uint16_t>(kCamera.size()));
    FrameImageBuffers scratch;
    std::vector<const void*> memory;
    for (int i = 0; i < 4; ++i) {
        // A source decodes the next frame into the frame's images (as FrameImageBuffers::handOver leaves them).
        std::copy(raw_depth.host(), raw_depth.host() + raw_depth.pixelCount(), frame.depth_raw.host());
        std::copy(raw_rgb.host(), raw_rgb.host() + raw_rgb.pixelCount(), frame.rgb.host());
        undistorter.apply(frame, scratch);
        ASSERT_TRUE(std::equal(frame.depth_raw.host(), frame.depth_raw.host() + frame.depth_raw.pixelCount(),
                               expected.depth_raw.host()));
        ASSERT_EQ(std::memcmp(frame.rgb.host(), expected.rgb.host(), frame.rgb.pixelCount() * sizeof(Vec4u8)), 0);
        memory.push_back(frame.depth_raw.host());
        memory.push_back(frame.rgb.host());
    }
    // Frames 0 and 2, 1 and 3 use the same memory; 0 and 1 do not.
    EXPECT_EQ(memory[0], memory[4]);
    EXPECT_EQ(memory[1], memory[5]);
    EXPECT_EQ(memory[2], memory[6]);
    EXPECT_EQ(memory[3], memory[7]);
    EXPECT_NE(memory[0], memory[2]);
    EXPECT_NE(memory[1], memory[3]);
}

// Labels follow the colour camera at their own resolution (here half), nearest-neighbour: only ids
// that were there (or kNoLabel outside the raw image), and a class patch lands where the pinhole sees it.
TEST(FrameUndistorter, LabelsAreUndistortedLikeColorAtTheirOwnResolution) {
    const Intrinsics half = kCamera.resized(kCamera.width / 2, kCamera.height / 2);
    const Vec2f ideal{35.f, 30.f};  // (70, 60) at full resolution, where the lens moves pixels a lot
    const Vec2f raw = distortPixel(half, kLens, ideal);
    Image<ClassId> labels(half.size());
    for (int y = 0; y < half.height; ++y)
        for (int x = 0; x < half.width; ++x)
            labels.at(x, y) = std::abs(x - raw.x) <= 1.5f && std::abs(y - raw.y) <= 1.5f
                                  ? ClassId(9)
                                  : ClassId(x < half.width / 2 ? 1 : 2);
    RGBDFrame frame = frameWith(Image<Vec4u8>(), Image<std::uint16_t>());
    frame.labels = std::move(labels);
    FrameUndistorter(calibWithLens()).apply(frame);
    ASSERT_EQ(frame.labels.size(), half.size());
    for (std::size_t i = 0; i < frame.labels.pixelCount(); ++i) {
        const ClassId v = frame.labels.host()[i];
        ASSERT_TRUE(v == 1 || v == 2 || v == 9 || v == kNoLabel) << "pixel " << i << " = " << v;
    }
    EXPECT_EQ(frame.labels.at(35, 30), 9);
}

TEST(FrameUndistorter, WithoutAColorCameraLabelsFollowTheDepthCamerasLens) {
    RGBDCalib depth_only;
    depth_only.depth = kCamera;
    depth_only.depth_distortion = kLens;
    const Vec2f ideal{70.f, 60.f};
    const Vec2f raw = distortPixel(kCamera, kLens, ideal);
    Image<ClassId> labels(kCamera.size());
    for (int y = 0; y < kCamera.height; ++y)
        for (int x = 0; x < kCamera.width; ++x)
            labels.at(x, y) = std::abs(x - raw.x) <= 1.5f && std::abs(y - raw.y) <= 1.5f ? ClassId(9) : ClassId(1);
    RGBDFrame frame = frameWith(Image<Vec4u8>(), Image<std::uint16_t>(kCamera.size()));
    frame.labels = std::move(labels);
    FrameUndistorter(depth_only).apply(frame);
    EXPECT_EQ(frame.labels.at(70, 60), 9);
}

TEST(FrameUndistorter, WithoutDistortionFramesStayAsTheyAre) {
    RGBDCalib calib;
    calib.rgb = kCamera;
    calib.depth = kCamera;
    const FrameUndistorter undistorter(calib);
    EXPECT_FALSE(undistorter.active());
    RGBDFrame frame = frameWith(test::makeRgb(kCamera.size(), 1), test::makeDepth(kCamera.size(), 2));
    undistorter.apply(frame);
    EXPECT_TRUE(test::samePixels(frame.rgb, test::makeRgb(kCamera.size(), 1)));
    EXPECT_TRUE(test::samePixels(frame.depth_raw, test::makeDepth(kCamera.size(), 2)));
}

TEST(FrameUndistorter, UndistortedCalibrationKeepsTheIntrinsicsWithoutDistortion) {
    const FrameUndistorter undistorter(calibWithLens());
    const RGBDCalib& calib = undistorter.undistortedCalib();
    EXPECT_FALSE(calib.rgb_distortion.any());
    EXPECT_FALSE(calib.depth_distortion.any());
    EXPECT_EQ(calib.rgb.fx, kCamera.fx);
    EXPECT_EQ(calib.depth.cy, kCamera.cy);
}

TEST(FrameUndistorter, AnImageOfTheWrongSizeIsAFrameError) {
    const FrameUndistorter undistorter(calibWithLens());
    RGBDFrame frame = frameWith(Image<Vec4u8>(), test::makeDepth({160, 120}, 0));
    try {
        undistorter.apply(frame);
        FAIL() << "no IoError";
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), "depth/0004.png");
        EXPECT_EQ(e.frame(), 4);
        EXPECT_NE(e.reason().find("160x120"), std::string::npos) << e.what();
        EXPECT_NE(e.reason().find("320x240"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace voxfuse
