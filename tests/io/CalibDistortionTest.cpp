// The optional lens distortion lines of calib.txt ("distortion_rgb k1 k2 p1 p2 k3", "distortion_depth ...").

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "IoTestUtil.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/CalibIO.h"

namespace voxfuse {
namespace {

using test::ScratchDir;
using test::writeBytes;

// A registered Kinect calibration: 13 content lines, the disparity line last (line 13).
const std::string kBase =
    "640 480\n525 525\n319.5 239.5\n\n"
    "640 480\n525 525\n319.5 239.5\n\n"
    "1 0 0 0\n0 1 0 0\n0 0 1 0\n\n"
    "affine 0.001 0\n";

RGBDCalib readText(const ScratchDir& dir, const std::string& text) {
    const std::string path = dir.file("calib.txt");
    writeBytes(path, text);
    return readCalib(path);
}

void expectDistortionEq(const LensDistortion& a, const LensDistortion& b) {
    EXPECT_FLOAT_EQ(a.k1, b.k1);
    EXPECT_FLOAT_EQ(a.k2, b.k2);
    EXPECT_FLOAT_EQ(a.p1, b.p1);
    EXPECT_FLOAT_EQ(a.p2, b.p2);
    EXPECT_FLOAT_EQ(a.k3, b.k3);
}

TEST(CalibDistortion, FilesWithoutDistortionLinesStillReadAsPinholeCameras) {
    ScratchDir dir;
    const RGBDCalib c = readText(dir, kBase);
    EXPECT_FALSE(c.rgb_distortion.any());
    EXPECT_FALSE(c.depth_distortion.any());
    for (const auto& entry : std::filesystem::directory_iterator(test::repositoryDir() / "calib")) {
        const RGBDCalib shipped = readCalib(entry.path().string());
        EXPECT_FALSE(shipped.rgb_distortion.any() || shipped.depth_distortion.any()) << entry.path();
    }
}

TEST(CalibDistortion, ReadsBothLinesInEitherOrder) {
    ScratchDir dir;
    const RGBDCalib c = readText(dir, kBase +
                                          "distortion_depth -0.1 0.02 0 0 0\n"
                                          "# the colour lens\n"
                                          "distortion_rgb 0.2624 -0.9531 -0.0054 0.0026 1.1633\n");
    expectDistortionEq(c.rgb_distortion, LensDistortion{0.2624f, -0.9531f, -0.0054f, 0.0026f, 1.1633f});
    expectDistortionEq(c.depth_distortion, LensDistortion{-0.1f, 0.02f, 0.f, 0.f, 0.f});
}

TEST(CalibDistortion, OneCameraAloneLeavesTheOtherUndistorted) {
    ScratchDir dir;
    const RGBDCalib c = readText(dir, kBase + "distortion_rgb 0.1 0 0 0 0\n");
    EXPECT_FLOAT_EQ(c.rgb_distortion.k1, 0.1f);
    EXPECT_FALSE(c.depth_distortion.any());
}

TEST(CalibDistortion, WriteReadRoundTripAndUndistortedFilesKeepTheOldFormat) {
    ScratchDir dir;
    RGBDCalib calib = readText(dir, kBase);
    const std::string plain = dir.file("plain.txt");
    writeCalib(plain, calib);
    EXPECT_EQ(test::readBytes(plain).find("distortion"), std::string::npos);

    calib.rgb_distortion = LensDistortion{0.25f, -0.5f, 0.001f, -0.002f, 0.125f};
    calib.depth_distortion = LensDistortion{-0.03f, 0.f, 0.f, 0.f, 0.f};
    const std::string distorted = dir.file("distorted.txt");
    writeCalib(distorted, calib);
    const RGBDCalib back = readCalib(distorted);
    expectDistortionEq(back.rgb_distortion, calib.rgb_distortion);
    expectDistortionEq(back.depth_distortion, calib.depth_distortion);
    EXPECT_FLOAT_EQ(back.disparity.a, 0.001f);
}

TEST(CalibDistortion, MalformedLinesNameTheLineAndTheProblem) {
    struct Case {
        const char* what;
        std::string text;
        int line;
        const char* reason;
    };
    const Case cases[] = {
        {"four numbers", kBase + "distortion_rgb 0.1 0.2 0 0\n", 14, "expected 5 numbers after 'distortion_rgb'"},
        {"not a number", kBase + "distortion_depth 0.1 x 0 0 0\n", 14, "not a number: 'x'"},
        {"non-finite", kBase + "distortion_depth 0.1 nan 0 0 0\n", 14, "non-finite value in distortion_depth"},
        {"given twice", kBase + "distortion_rgb 0 0 0 0 0\n\ndistortion_rgb 0 0 0 0 0\n", 16, "given twice"},
        {"unknown keyword", kBase + "distortion_ir 0 0 0 0 0\n", 14, "unexpected content after the disparity"},
    };
    for (const Case& c : cases) {
        ScratchDir dir;
        try {
            readText(dir, c.text);
            ADD_FAILURE() << c.what << ": no ParseError";
        } catch (const ParseError& e) {
            EXPECT_EQ(e.line(), c.line) << c.what << ": " << e.what();
            EXPECT_NE(e.reason().find(c.reason), std::string::npos) << c.what << ": " << e.what();
        }
    }
}

}  // namespace
}  // namespace voxfuse
