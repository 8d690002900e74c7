#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "IoTestUtil.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/CalibIO.h"

namespace voxfuse {
namespace {

using test::ScratchDir;
using test::writeBytes;

// InfiniTAM's Teddy calib.txt; line 13 is the disparity line.
const std::string kRgbBlock = "640 480\n504.261 503.905\n352.457 272.202\n";
const std::string kDepthBlock = "640 480\n573.71 574.394\n346.471 249.031\n";
const std::string kExtrinsics =
    "0.999749 0.00518867 0.0217975 0.0243073\n"
    "-0.0051649 0.999986 -0.0011465 -0.000166518\n"
    "-0.0218031 0.00103363 0.999762 0.0151706\n";
std::string calibText(const std::string& disparity_line) {
    return kRgbBlock + "\n" + kDepthBlock + "\n" + kExtrinsics + "\n" + disparity_line + "\n";
}

RGBDCalib readCalibText(const ScratchDir& dir, const std::string& text) {
    const std::string path = dir.file("calib.txt");
    writeBytes(path, text);
    return readCalib(path);
}

void expectCameraEq(const Intrinsics& a, const Intrinsics& b) {
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_FLOAT_EQ(a.fx, b.fx);
    EXPECT_FLOAT_EQ(a.fy, b.fy);
    EXPECT_FLOAT_EQ(a.cx, b.cx);
    EXPECT_FLOAT_EQ(a.cy, b.cy);
}

void expectCalibEq(const RGBDCalib& a, const RGBDCalib& b) {
    expectCameraEq(a.rgb, b.rgb);
    expectCameraEq(a.depth, b.depth);
    for (int i = 0; i < 16; ++i) EXPECT_FLOAT_EQ(a.T_depth_rgb.m[i], b.T_depth_rgb.m[i]) << "element " << i;
    EXPECT_EQ(a.disparity.type, b.disparity.type);
    EXPECT_FLOAT_EQ(a.disparity.a, b.disparity.a);
    EXPECT_FLOAT_EQ(a.disparity.b, b.disparity.b);
}

TEST(CalibIO, ReadsInfiniTamExampleWithBareKinectDisparity) {
    ScratchDir dir;
    const RGBDCalib c = readCalibText(dir, calibText("1135.09 0.0819141"));
    expectCameraEq(c.rgb, Intrinsics{640, 480, 504.261f, 503.905f, 352.457f, 272.202f});
    expectCameraEq(c.depth, Intrinsics{640, 480, 573.71f, 574.394f, 346.471f, 249.031f});
    EXPECT_FLOAT_EQ(c.T_depth_rgb(0, 0), 0.999749f);
    EXPECT_FLOAT_EQ(c.T_depth_rgb(0, 3), 0.0243073f);
    EXPECT_FLOAT_EQ(c.T_depth_rgb(1, 0), -0.0051649f);
    EXPECT_FLOAT_EQ(c.T_depth_rgb(1, 3), -0.000166518f);
    EXPECT_FLOAT_EQ(c.T_depth_rgb(2, 2), 0.999762f);
    EXPECT_FLOAT_EQ(c.T_depth_rgb(2, 3), 0.0151706f);
    EXPECT_FLOAT_EQ(c.T_depth_rgb(3, 0), 0.f);
    EXPECT_FLOAT_EQ(c.T_depth_rgb(3, 3), 1.f);
    EXPECT_EQ(c.disparity.type, DisparityCalib::Type::Kinect);
    EXPECT_FLOAT_EQ(c.disparity.a, 1135.09f);
    EXPECT_FLOAT_EQ(c.disparity.b, 0.0819141f);
}

TEST(CalibIO, ReadsKinectKeywordDisparity) {
    ScratchDir dir;
    const RGBDCalib c = readCalibText(dir, calibText("kinect 1135.09 0.0819141"));
    EXPECT_EQ(c.disparity.type, DisparityCalib::Type::Kinect);
    EXPECT_FLOAT_EQ(c.disparity.a, 1135.09f);
    EXPECT_FLOAT_EQ(c.disparity.b, 0.0819141f);
}

TEST(CalibIO, ReadsAffineKeywordDisparity) {
    ScratchDir dir;
    const RGBDCalib c = readCalibText(dir, calibText("affine 0.0002 0.0"));
    EXPECT_EQ(c.disparity.type, DisparityCalib::Type::Affine);
    EXPECT_FLOAT_EQ(c.disparity.a, 0.0002f);
    EXPECT_FLOAT_EQ(c.disparity.b, 0.f);
    EXPECT_FLOAT_EQ(c.disparity.toMetres(5000, c.depth.fx), 1.f);
}

TEST(CalibIO, AcceptsCommentsAndMissingBlankLines) {
    ScratchDir dir;
    const std::string with_comments = "# my camera\n\n" + kRgbBlock + "  # depth next\n" + kDepthBlock +
                                      "\n\n# extrinsics\n" + kExtrinsics + "affine 0.001 0\n\n# end\n";
    const RGBDCalib a = readCalibText(dir, with_comments);
    const RGBDCalib b =
        readCalibText(dir, kRgbBlock + kDepthBlock + kExtrinsics + "affine 0.001 0");  // no final newline
    expectCalibEq(a, b);
    EXPECT_FLOAT_EQ(a.depth.fx, 573.71f);
}

TEST(CalibIO, AcceptsWindowsLineEndings) {
    ScratchDir dir;
    std::string text = calibText("affine 0.001 0");
    std::string crlf;
    for (char ch : text) crlf += ch == '\n' ? std::string("\r\n") : std::string(1, ch);
    EXPECT_FLOAT_EQ(readCalibText(dir, crlf).rgb.fx, 504.261f);
}

TEST(CalibIO, WriteThenReadGivesTheSameCalibration) {
    ScratchDir dir;
    for (const char* disparity : {"1135.09 0.0819141", "affine 0.000123 -0.01"}) {
        const RGBDCalib original = readCalibText(dir, calibText(disparity));
        const std::string path = dir.file("written.txt");
        writeCalib(path, original);
        const RGBDCalib again = readCalib(path);
        expectCalibEq(original, again);
        // Floats must survive exactly, not just approximately.
        EXPECT_EQ(original.rgb.fx, again.rgb.fx);
        EXPECT_EQ(original.T_depth_rgb.m[3], again.T_depth_rgb.m[3]);
        EXPECT_EQ(original.disparity.b, again.disparity.b);
    }
    // Shortest exact digits, so that written files stay readable.
    const std::string path = dir.file("written.txt");
    writeCalib(path, readCalibText(dir, calibText("1135.09 0.0819141")));
    const std::string written = test::readBytes(path);
    EXPECT_NE(written.find("640 480\n504.261 503.905\n352.457 272.202\n"), std::string::npos) << written;
    EXPECT_NE(written.find("\nkinect 1135.09 0.0819141\n"), std::string::npos) << written;
}

struct MalformedCase {
    const char* what;
    std::string text;
    int line;
    const char* reason_part;
};

// Each case, written to a file, is refused with a ParseError naming the file, its line and the reason.
void expectParseErrors(const std::vector<MalformedCase>& cases) {
    ScratchDir dir;
    for (const MalformedCase& c : cases) {
        SCOPED_TRACE(c.what);
        const std::string path = dir.file("bad.txt");
        writeBytes(path, c.text);
        try {
            readCalib(path);
            ADD_FAILURE() << "no ParseError for: " << c.what;
        } catch (const ParseError& e) {
            EXPECT_EQ(e.line(), c.line) << e.what();
            EXPECT_NE(std::string(e.what()).find(path + ":" + std::to_string(c.line)), std::string::npos) << e.what();
            EXPECT_NE(e.reason().find(c.reason_part), std::string::npos) << e.what();
        }
    }
}

std::string replaceLine(const std::string& text, int line_number, const std::string& replacement) {
    std::string out;
    int n = 1;
    std::size_t start = 0;
    while (start < text.size()) {
        std::size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        out += (n == line_number ? replacement : text.substr(start, end - start)) + "\n";
        start = end + 1;
        ++n;
    }
    return out;
}

TEST(CalibIO, MalformedFilesNameFileLineAndReason) {
    const std::string good = calibText("1135.09 0.0819141");  // 13 lines
    const std::vector<MalformedCase> cases = {
        {"three numbers for a size", replaceLine(good, 1, "640 480 3"), 1, "expected 2 integers"},
        {"non-number in a size", replaceLine(good, 1, "640 abc"), 1, "not an integer: 'abc'"},
        {"fractional width", replaceLine(good, 5, "640.5 480"), 5, "not an integer: '640.5'"},
        {"zero height", replaceLine(good, 1, "640 0"), 1, "must be positive"},
        {"negative focal length", replaceLine(good, 2, "-504.261 503.905"), 2, "focal lengths must be positive"},
        {"zero focal length", replaceLine(good, 6, "573.71 0"), 6, "focal lengths must be positive"},
        {"focal length of no real camera", replaceLine(good, 2, "1e-20 503.905"), 2,
         "give no field of view between 1 and 170 degrees"},
        {"focal length in metres", replaceLine(good, 6, "0.0035 0.0035"), 6,
         "give no field of view between 1 and 170 degrees"},
        {"non-number focal length", replaceLine(good, 6, "573.71 x"), 6, "not a number: 'x'"},
        {"number with garbage suffix", replaceLine(good, 3, "352.457 272.202abc"), 3, "not a number: '272.202abc'"},
        {"trailing garbage", replaceLine(good, 7, "346.471 249.031 junk"), 7, "expected 2 numbers"},
        {"nan focal length", replaceLine(good, 2, "nan 503.905"), 2, "non-finite"},
        {"short extrinsics row", replaceLine(good, 10, "-0.0051649 0.999986 -0.0011465"), 10, "expected 4 numbers"},
        {"extrinsics not a rotation", replaceLine(good, 9, "2 0.00518867 0.0217975 0.0243073"), 9, "not a rotation"},
        {"unknown disparity keyword", replaceLine(good, 13, "disparity 1135.09 0.08"), 13,
         "unknown disparity calibration type 'disparity'"},
        {"affine with three numbers", replaceLine(good, 13, "affine 0.001 0 5"), 13,
         "expected 2 numbers after the disparity type 'affine'"},
        {"bare disparity with one number", replaceLine(good, 13, "1135.09"), 13, "expected 2 numbers"},
        {"affine zero scale", replaceLine(good, 13, "affine 0 0"), 13, "affine depth scale must be positive"},
        {"kinect non-positive k2", replaceLine(good, 13, "kinect 1135.09 0"), 13, "k2 must be positive"},
        {"content after the disparity line", good + "\n7 7\n", 15, "unexpected content after the disparity"},
        {"missing disparity line", kRgbBlock + "\n" + kDepthBlock + "\n" + kExtrinsics, 11, "unexpected end of file"},
        {"missing extrinsics row", kRgbBlock + "\n" + kDepthBlock + "\n" + "1 0 0 0\n0 1 0 0\n\n", 11,
         "unexpected end of file: expected row 3"},
        {"only the rgb block", kRgbBlock, 3, "unexpected end of file: expected depth camera image size"},
        {"empty file", "", 1, "unexpected end of file"},
        {"comment lines count", "# header\n# more\n" + replaceLine(good, 1, "640"), 3, "expected 2 integers"},
    };
    expectParseErrors(cases);
}

// Values are checked as the floats they are stored in, and for what a camera can be.
TEST(CalibIO, ValuesAreCheckedInTheTypeTheyAreUsedIn) {
    const std::string good = calibText("affine 0.001 0");
    const std::vector<MalformedCase> cases = {
        {"focal length finite as a double, infinite as a float", replaceLine(good, 2, "1e39 503.905"), 2,
         "non-finite value '1e39'"},
        {"focal length that rounds to zero as a float", replaceLine(good, 6, "1e-50 574.394"), 6,
         "focal lengths must be positive"},
        {"principal point outside the image", replaceLine(good, 3, "900 272.202"), 3,
         "principal point (900, 272.202) lies outside"},
        {"negative principal point", replaceLine(good, 7, "346.471 -20"), 7, "lies outside its 640x480 image"},
        {"principal point 1e39", replaceLine(good, 7, "1e39 249.031"), 7, "non-finite value"},
        {"absurd image size", replaceLine(good, 5, "1000000 480"), 5, "larger than 16384 pixels"},
        {"translation infinite as a float", replaceLine(good, 9, "0.999749 0.00518867 0.0217975 4e38"), 9,
         "non-finite value '4e38'"},
        {"a reflection is no rotation", replaceLine(good, 11, "0.0218031 -0.00103363 -0.999762 0.0151706"), 9,
         "reflection"},
        {"affine scale that rounds to zero", replaceLine(good, 13, "affine 1e-50 0"), 13,
         "affine depth scale must be positive"},
        {"affine offset infinite as a float", replaceLine(good, 13, "affine 0.001 1e39"), 13,
         "non-finite value in the disparity"},
        {"distortion infinite as a float", good + "distortion_rgb 0.1 1e39 0 0 0\n", 14,
         "non-finite value in distortion_rgb"},
        {"a line longer than any calibration's", replaceLine(good, 2, std::string(70000, '5')), 2,
         "line longer than 65536 bytes"},
        {"control bytes are shown escaped", replaceLine(good, 13, "\x1b[2Jaffine 0.001 0"), 13, "'\\x1b[2Jaffine'"},
    };
    expectParseErrors(cases);
}

// Values a file can hold but no depth camera has are refused with the reason, on their line.
TEST(CalibIO, ValuesOfNoRealCameraAreRefused) {
    const std::string good = calibText("affine 0.001 0");
    const std::vector<MalformedCase> cases = {
        {"metres per unit given as 1 (millimetres read as metres)", replaceLine(good, 13, "affine 1 0"), 13,
         "coarser than any depth camera"},
        {"a scale that reaches no depth camera's range", replaceLine(good, 13, "affine 1e-9 0"), 13,
         "no depth camera's range"},
        {"an offset of metres", replaceLine(good, 13, "affine 0.001 5"), 13, "depth offset 5 m"},
        {"a Kinect baseline in millimetres", replaceLine(good, 13, "kinect 1135.09 81.9"), 13, "Kinect baseline"},
        {"a Kinect offset that leaves every sample behind the camera", replaceLine(good, 13, "kinect -5 0.08"), 13,
         "no sample a positive depth"},
        {"a radial factor that reaches zero", good + "distortion_depth -5 0 0 0 0\n", 14, "folds the image"},
        {"a radial model that folds the image", good + "distortion_rgb -3 0 0 0 0\n", 14, "folds the image"},
        {"a tangential term that moves corners by more than their radius", good + "distortion_rgb 0 0 2 0 0\n", 14,
         "moves an image corner"},
    };
    expectParseErrors(cases);
}

// Real cameras' values pass without a word; unusual ones pass with a warning that names them.
TEST(CalibIO, UnusualValuesPassWithAWarning) {
    ScratchDir dir;
    const auto warnings = [&](const std::string& text) {
        testing::internal::CaptureStderr();
        readCalibText(dir, text);
        return testing::internal::GetCapturedStderr();
    };
    // TUM fr1's colour lens (Kinect v1), a RealSense's 0.1 mm depth units, the Kinect's own disparity form.
    EXPECT_EQ(warnings(calibText("affine 0.001 0") + "distortion_rgb 0.262383 -0.953104 -0.005358 0.002628 1.163314\n"),
              "");
    EXPECT_EQ(warnings(calibText("affine 0.0001 0")), "");
    EXPECT_EQ(warnings(calibText("1135.09 0.0819141")), "");
    const std::string coarse = warnings(calibText("affine 0.01 0"));
    EXPECT_NE(coarse.find("warning"), std::string::npos);
    EXPECT_NE(coarse.find("10 mm apart at 1 m"), std::string::npos) << coarse;
    EXPECT_NE(warnings(calibText("affine 0.001 0.3")).find("depth offset 0.3 m"), std::string::npos);
    EXPECT_NE(
        warnings(replaceLine(calibText("affine 0.001 0"), 9, "0.999749 0.00518867 0.0217975 24.3073")).find("m apart"),
        std::string::npos);
    EXPECT_NE(warnings(calibText("affine 0.001 0") + "distortion_depth -0.55 0 0 0 0\n").find("distortion_depth"),
              std::string::npos);
    EXPECT_NE(warnings(calibText("affine 0.001 0") + "distortion_rgb -0.8 0 0 0 0\n").find("folds the image"),
              std::string::npos);
}

// Samples the conversion maps to no depth cannot come from the calibrated camera; 0 is no measurement.
TEST(CalibIO, SamplesTheConversionGivesNoDepthAreCounted) {
    Image<std::uint16_t> raw(Vec2i{4, 1});
    const std::uint16_t values[4] = {0, 500, 1000, 2000};
    std::copy(values, values + 4, raw.host());
    EXPECT_EQ(depthSamplesWithoutDepth(raw, DisparityCalib::kinect(1000.f, 0.075f), 580.f), 2u);
    EXPECT_EQ(depthSamplesWithoutDepth(raw, DisparityCalib::affine(0.001f), 580.f), 0u);
    EXPECT_EQ(depthSamplesWithoutDepth(raw, DisparityCalib::affine(0.001f, -0.8f), 580.f), 1u);
}

TEST(CalibIO, AFolderGivenForTheFileSaysSo) {
    ScratchDir dir;
    try {
        readCalib(dir.path());
        FAIL() << "a folder was read as a calibration";
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), dir.path());
        EXPECT_NE(e.reason().find("is a folder, not a file"), std::string::npos) << e.what();
    }
}

TEST(CalibIO, MissingFileIsAnIoErrorNotAParseError) {
    const std::string path = "/nonexistent/voxfuse/calib.txt";
    try {
        readCalib(path);
        FAIL() << "expected IoError";
    } catch (const ParseError& e) {
        FAIL() << "a missing file is not a parse error: " << e.what();
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), path);
        EXPECT_NE(e.reason().find("cannot open"), std::string::npos);
    }
}

TEST(CalibIO, WriteToUnwritablePathThrows) {
    EXPECT_THROW(writeCalib("/nonexistent/voxfuse/calib.txt", kinectV1DefaultCalib()), IoError);
}

TEST(CalibIO, KnownCalibrations) {
    const RGBDCalib kinect = kinectV1DefaultCalib();
    expectCameraEq(kinect.depth, Intrinsics{640, 480, 525.f, 525.f, 319.5f, 239.5f});
    expectCameraEq(kinect.rgb, kinect.depth);
    EXPECT_EQ(kinect.disparity.type, DisparityCalib::Type::Affine);
    EXPECT_FLOAT_EQ(kinect.disparity.a, 0.001f);

    expectCameraEq(tumCalib(1).depth, Intrinsics{640, 480, 517.3f, 516.5f, 318.6f, 255.3f});
    expectCameraEq(tumCalib(2).depth, Intrinsics{640, 480, 520.9f, 521.0f, 325.1f, 249.7f});
    expectCameraEq(tumCalib(3).rgb, Intrinsics{640, 480, 535.4f, 539.2f, 320.1f, 247.6f});
    EXPECT_FLOAT_EQ(tumCalib(3).disparity.toMetres(5000, 535.4f), 1.f);
    EXPECT_THROW(tumCalib(0), ConfigError);
    EXPECT_THROW(tumCalib(4), ConfigError);
}

TEST(CalibIO, EveryFileInCalibFolderParses) {
    const auto calib_dir = test::repositoryDir() / "calib";
    ASSERT_TRUE(std::filesystem::is_directory(calib_dir)) << calib_dir;
    int files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(calib_dir)) {
        if (entry.path().extension() != ".txt") continue;
        SCOPED_TRACE(entry.path().string());
        RGBDCalib c;
        ASSERT_NO_THROW(c = readCalib(entry.path().string()));
        EXPECT_TRUE(c.rgb.valid());
        EXPECT_TRUE(c.depth.valid());
        ++files;
    }
    EXPECT_GE(files, 5);
}

TEST(CalibIO, CalibFilesMatchBuiltInCalibrations) {
    const auto calib_dir = test::repositoryDir() / "calib";
    for (int n = 1; n <= 3; ++n) {
        SCOPED_TRACE(n);
        expectCalibEq(readCalib((calib_dir / ("tum_fr" + std::to_string(n) + ".txt")).string()), tumCalib(n));
    }
    expectCalibEq(readCalib((calib_dir / "kinect_v1_default.txt").string()), kinectV1DefaultCalib());
    const RGBDCalib sample = readCalib((calib_dir / "kinfu_sample.txt").string());
    EXPECT_NEAR(sample.depth.fx, 615.195f, 1e-3);
    EXPECT_FLOAT_EQ(sample.disparity.a, 0.001f);
}

}  // namespace
}  // namespace voxfuse
