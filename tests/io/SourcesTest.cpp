#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "IoTestUtil.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/OpenNISource.h"
#include "voxfuse/io/CalibIO.h"
#include "voxfuse/io/FrameFolderSource.h"
#include "voxfuse/io/ImageIO.h"
#include "voxfuse/io/ImageSource.h"
#include "voxfuse/io/PpmPgmSource.h"
#include "voxfuse/io/TrajectoryIO.h"
#include "voxfuse/io/TumSource.h"

namespace voxfuse {
namespace {

using test::makeDepth;
using test::makeRgb;
using test::readBytes;
using test::samePixels;
using test::ScratchDir;
using test::writeBytes;

const Vec2i kSmall{4, 3};

// A registered calibration for tiny test images.
std::string writeSmallCalib(const std::string& path, float depth_scale) {
    RGBDCalib calib;
    calib.rgb = Intrinsics{kSmall.x, kSmall.y, 5.f, 5.f, 1.5f, 1.f};
    calib.depth = calib.rgb;
    calib.disparity = DisparityCalib::affine(depth_scale);
    writeCalib(path, calib);
    return path;
}

bool containsText(const std::string& haystack, const std::string& needle) {
    return haystack.find(needle) != std::string::npos;
}

// ----------------------------------------------------------------------------------------------
// TUM folders

// rgb and depth images carry the seed they were made with, so a frame shows which files it paired.
struct HandMadeTumFolder {
    ScratchDir dir;
    HandMadeTumFolder() {
        writeSmallCalib(dir.file("calib.txt"), 0.0002f);
        std::string rgb_list = "# color images\n# timestamp filename\n";
        const std::vector<std::pair<std::string, int>> rgb = {
            {"1.000000", 10}, {"1.033000", 11}, {"1.067000", 12}, {"1.250000", 13}};
        for (const auto& [time, seed] : rgb) {
            writePNG(dir.file("rgb/" + time + ".png"), makeRgb(kSmall, seed));
            rgb_list += time + " rgb/" + time + ".png\n";
        }
        rgb_list += "1.300000 rgb/not_on_disk.png\n";
        writeBytes(dir.file("rgb.txt"), rgb_list);

        // 1.005 -> rgb 1.000; 1.040 -> rgb 1.033; 1.060 and 1.072 both want rgb 1.067 (the closer,
        // 1.072, wins and 1.060 is dropped); 1.150 has nothing within 0.02 s and is dropped.
        std::string depth_list = "# depth maps\n";
        const std::vector<std::pair<std::string, int>> depth = {
            {"1.005000", 20}, {"1.040000", 21}, {"1.060000", 22}, {"1.072000", 23}, {"1.150000", 24}};
        for (const auto& [time, seed] : depth) {
            writeDepthPNG(dir.file("depth/" + time + ".png"), makeDepth(kSmall, seed));
            depth_list += time + " depth/" + time + ".png\n";
        }
        writeBytes(dir.file("depth.txt"), depth_list);

        writeBytes(dir.file("groundtruth.txt"),
                   "# ground truth\n1.000 0 0 0 0 0 0 1\n1.010 1 0 0 0 0 0 1\n1.050 2 0 0 0 0 0 1\n");
    }
};

TEST(TumSource, AssociatesByNearestTimestampOnHandMadeFolder) {
    HandMadeTumFolder folder;
    TumSource source(folder.dir.path());
    EXPECT_EQ(source.frameCount(), 3);
    EXPECT_EQ(source.droppedDepthFrames(), 2);
    EXPECT_EQ(source.missingListedFiles(), 1);
    EXPECT_TRUE(containsText(source.description(), "3 frames")) << source.description();
    EXPECT_TRUE(containsText(source.description(), "2 depth frames without an rgb image")) << source.description();
    EXPECT_FLOAT_EQ(source.calib().depth.fx, 5.f);  // calib.txt in the folder wins over guessing
    EXPECT_EQ(source.groundTruth().size(), 3u);

    const std::vector<std::pair<int, int>> expected_seeds = {{20, 10}, {21, 11}, {23, 12}};  // depth, rgb
    const std::vector<double> expected_times = {1.005, 1.040, 1.072}, expected_rgb_times = {1.000, 1.033, 1.067};
    RGBDFrame frame;
    for (int i = 0; i < 3; ++i) {
        SCOPED_TRACE(i);
        ASSERT_TRUE(source.next(frame));
        EXPECT_EQ(frame.index, i);
        EXPECT_DOUBLE_EQ(frame.timestamp_s, expected_times[std::size_t(i)]);
        EXPECT_DOUBLE_EQ(frame.rgb_timestamp_s, expected_rgb_times[std::size_t(i)]);
        EXPECT_TRUE(samePixels(frame.depth_raw, makeDepth(kSmall, expected_seeds[std::size_t(i)].first)));
        EXPECT_TRUE(samePixels(frame.rgb, makeRgb(kSmall, expected_seeds[std::size_t(i)].second)));
    }
    EXPECT_FALSE(source.next(frame));
    EXPECT_FALSE(source.next(frame));
}

// A listed depth image missing between ones on disk is an unreadable frame at its own place, named,
// and the frames after it keep their indices; the rgb line after the last image on disk (a trimmed
// copy's longer list) is left out.
TEST(TumSource, AListedImageMissingBetweenOnesOnDiskIsAnUnreadableFrameInItsPlace) {
    HandMadeTumFolder folder;
    const std::string missing = folder.dir.file("depth/1.040000.png");
    std::filesystem::remove(missing);
    TumSource source(folder.dir.path());
    EXPECT_EQ(source.frameCount(), 3);
    EXPECT_EQ(source.missingListedFiles(), 2);
    EXPECT_TRUE(containsText(source.description(), "1 listed images beyond those on disk left out"))
        << source.description();
    EXPECT_TRUE(containsText(source.description(),
                             "1 listed images missing between those on disk (their frames are unreadable)"))
        << source.description();
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.index, 0);
    try {
        source.next(frame);
        ADD_FAILURE() << "the missing depth image was not reported";
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), missing);
        EXPECT_EQ(e.frame(), 1);
    }
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.index, 2);
    EXPECT_DOUBLE_EQ(frame.timestamp_s, 1.072);
    EXPECT_FALSE(source.next(frame));
}

// Frames read into one RGBDFrame trade images with the source: from the third frame on, each is
// decoded into memory an earlier frame had, so a sequence allocates no image memory per frame.
TEST(TumSource, FramesAreDecodedIntoTheMemoryOfEarlierFrames) {
    HandMadeTumFolder folder;
    TumSource source(folder.dir.path());
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    const std::uint16_t* first_depth = frame.depth_raw.host();
    const Vec4u8* first_rgb = frame.rgb.host();
    ASSERT_TRUE(source.next(frame));
    EXPECT_NE(frame.depth_raw.host(), first_depth)
        << "the second frame needs images of its own: the first is the caller's";
    // Were the first frame's images freed, these would take their memory (allocators reuse the last freed).
    const Image<std::uint16_t> depth_blocker(kSmall);
    const Image<Vec4u8> rgb_blocker(kSmall);
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.depth_raw.host(), first_depth);
    EXPECT_EQ(frame.rgb.host(), first_rgb);
    EXPECT_TRUE(samePixels(frame.depth_raw, makeDepth(kSmall, 23)));
    EXPECT_TRUE(samePixels(frame.rgb, makeRgb(kSmall, 12)));
}

TEST(TumSource, GroundTruthIsInterpolatedWithinTheGap) {
    HandMadeTumFolder folder;
    TumSource source(folder.dir.path());
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));  // t = 1.005: halfway between the samples at 1.000 and 1.010
    ASSERT_TRUE(frame.has_ground_truth);
    EXPECT_NEAR(frame.T_world_camera_gt(0, 3), 0.5f, 1e-4f);
    ASSERT_TRUE(source.next(frame));  // t = 1.040: 1.010 is 0.03 before, so the nearest sample, 1.050
    ASSERT_TRUE(frame.has_ground_truth);
    EXPECT_NEAR(frame.T_world_camera_gt(0, 3), 2.f, 1e-6f);
    ASSERT_TRUE(source.next(frame));  // t = 1.072: 0.022 after the last sample
    EXPECT_FALSE(frame.has_ground_truth);
}

TEST(TumSource, CalibrationGuessedFromFolderName) {
    ScratchDir dir;
    auto makeFolder = [&](const std::string& name) {
        writeBytes(dir.file(name + "/rgb.txt"), "# empty\n");
        writeBytes(dir.file(name + "/depth.txt"), "# empty\n");
        return dir.path() + "/" + name;
    };
    EXPECT_FLOAT_EQ(TumSource(makeFolder("rgbd_dataset_freiburg2_desk")).calib().depth.fx, 520.9f);
    EXPECT_FLOAT_EQ(TumSource(makeFolder("tum_fr1_xyz") + "/").calib().rgb.fy, 516.5f);
    EXPECT_FLOAT_EQ(TumSource(makeFolder("Freiburg3_Teddy")).calib().rgb.cx, 320.1f);

    const TumSource unknown(makeFolder("some_recording"));  // warns on stderr
    EXPECT_FLOAT_EQ(unknown.calib().depth.fx, 525.f);
    EXPECT_EQ(unknown.calib().disparity.type, DisparityCalib::Type::Affine);
    EXPECT_FLOAT_EQ(unknown.calib().disparity.a, 0.0002f);
    EXPECT_EQ(unknown.frameCount(), 0);

    const std::string explicit_calib = writeSmallCalib(dir.file("mine.txt"), 0.001f);
    EXPECT_FLOAT_EQ(TumSource(makeFolder("rgbd_dataset_freiburg2_desk"), explicit_calib).calib().depth.fx, 5.f);
}

TEST(TumSource, MalformedListNamesTheLine) {
    HandMadeTumFolder folder;
    writeBytes(folder.dir.file("depth.txt"), "# depth maps\n1.005 depth/1.005000.png\n1.04x depth/1.040000.png\n");
    try {
        TumSource source(folder.dir.path());
        FAIL() << "expected ParseError";
    } catch (const ParseError& e) {
        EXPECT_EQ(e.line(), 3);
        EXPECT_TRUE(containsText(e.what(), "depth.txt:3")) << e.what();
        EXPECT_TRUE(containsText(e.reason(), "not a timestamp: '1.04x'")) << e.what();
    }
}

TEST(TumSource, CorruptFrameThrowsThenContinues) {
    HandMadeTumFolder folder;
    writeBytes(folder.dir.file("depth/1.040000.png"), "not a png");
    TumSource source(folder.dir.path());
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    try {
        source.next(frame);
        FAIL() << "expected IoError";
    } catch (const IoError& e) {
        EXPECT_EQ(e.frame(), 1);
        EXPECT_TRUE(containsText(e.file(), "1.040000.png")) << e.what();
    }
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.index, 2);
    EXPECT_FALSE(source.next(frame));
}

// The colour decodes on a thread of its own beside the depth: either failing is the frame's error,
// named by its file, and the depth's when both fail.
TEST(TumSource, ABadColorImageOrBothBadNameTheFile) {
    HandMadeTumFolder folder;
    writeBytes(folder.dir.file("rgb/1.033000.png"), "not a png");
    writeBytes(folder.dir.file("rgb/1.067000.png"), "not a png either");
    writeBytes(folder.dir.file("depth/1.072000.png"), "nor this");
    TumSource source(folder.dir.path());
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    for (const char* expected : {"rgb/1.033000.png", "depth/1.072000.png"}) {
        try {
            source.next(frame);
            FAIL() << "expected IoError naming " << expected;
        } catch (const IoError& e) {
            EXPECT_TRUE(containsText(e.file(), expected)) << e.what();
        }
    }
    EXPECT_FALSE(source.next(frame)) << "the folder's three frames were read";
}

// ----------------------------------------------------------------------------------------------
// PPM/PGM sequences

struct PpmPgmFolder {
    ScratchDir dir;
    std::string calib;
    explicit PpmPgmFolder(const std::vector<int>& indices) {
        calib = writeSmallCalib(dir.file("calib.txt"), 0.001f);
        for (int i : indices) {
            char name[32];
            std::snprintf(name, sizeof name, "%04d", i);
            writePPM(dir.file(std::string("rgb/") + name + ".ppm"), makeRgb(kSmall, i));
            writePGM16(dir.file(std::string("depth/") + name + ".pgm"), makeDepth(kSmall, i));
        }
    }
    std::string rgbPattern() const { return dir.path() + "/rgb/%04i.ppm"; }
    std::string depthPattern() const { return dir.path() + "/depth/%04i.pgm"; }
};

TEST(PpmPgmSource, AMissingFrameIsReportedAndTheSequenceGoesOn) {
    PpmPgmFolder folder({0, 1, 2, 4});  // 3 is missing
    PpmPgmSource source(folder.rgbPattern(), folder.depthPattern(), folder.calib);
    EXPECT_EQ(source.frameCount(), 5);
    EXPECT_TRUE(containsText(source.description(), "1 of them missing")) << source.description();
    RGBDFrame frame;
    for (int i : {0, 1, 2}) {
        SCOPED_TRACE(i);
        ASSERT_TRUE(source.next(frame));
        EXPECT_EQ(frame.index, i);
        EXPECT_DOUBLE_EQ(frame.timestamp_s, i / 30.0);
        EXPECT_TRUE(samePixels(frame.depth_raw, makeDepth(kSmall, i)));
        EXPECT_TRUE(samePixels(frame.rgb, makeRgb(kSmall, i)));
        EXPECT_FALSE(frame.has_ground_truth);
    }
    try {
        source.next(frame);
        FAIL() << "the gap at index 3 went unreported";
    } catch (const IoError& e) {
        EXPECT_EQ(e.frame(), 3);
        EXPECT_TRUE(containsText(e.file(), "0003.pgm")) << e.what();
        EXPECT_TRUE(containsText(e.reason(), "missing")) << e.what();
    }
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.index, 4);
    EXPECT_TRUE(samePixels(frame.depth_raw, makeDepth(kSmall, 4)));
    EXPECT_FALSE(source.next(frame));
    EXPECT_FALSE(source.next(frame));
    EXPECT_TRUE(source.groundTruth().empty());
}

TEST(PpmPgmSource, AMissingColorFileIsThatFramesError) {
    PpmPgmFolder folder({0, 1, 2});
    std::filesystem::remove(folder.dir.path() + "/rgb/0001.ppm");
    PpmPgmSource source(folder.rgbPattern(), folder.depthPattern(), folder.calib);
    EXPECT_EQ(source.frameCount(), 3);
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    try {
        source.next(frame);
        FAIL() << "a frame without its colour file went unreported";
    } catch (const IoError& e) {
        EXPECT_EQ(e.frame(), 1);
        EXPECT_TRUE(containsText(e.file(), "0001.ppm")) << e.what();
    }
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.index, 2);
}

TEST(PpmPgmSource, FirstIndexAndDepthOnly) {
    PpmPgmFolder folder({0, 1, 2});
    PpmPgmSource source("", folder.depthPattern(), folder.calib, 1);
    EXPECT_EQ(source.frameCount(), 2);
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.index, 0);
    EXPECT_DOUBLE_EQ(frame.timestamp_s, 1 / 30.0);
    EXPECT_TRUE(samePixels(frame.depth_raw, makeDepth(kSmall, 1)));
    EXPECT_TRUE(frame.rgb.empty());
}

TEST(PpmPgmSource, CorruptMiddleFrameThrowsThenContinues) {
    PpmPgmFolder folder({0, 1, 2});
    const std::string bad = folder.dir.path() + "/depth/0001.pgm";
    const std::string bytes = readBytes(bad);
    writeBytes(bad, bytes.substr(0, bytes.size() - 5));

    PpmPgmSource source(folder.rgbPattern(), folder.depthPattern(), folder.calib);
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.index, 0);
    try {
        source.next(frame);
        FAIL() << "expected IoError for the truncated frame";
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), bad);
        EXPECT_EQ(e.frame(), 1);
        EXPECT_TRUE(containsText(e.reason(), "truncated")) << e.what();
        EXPECT_TRUE(containsText(e.what(), "frame 1")) << e.what();
    }
    EXPECT_EQ(frame.index, 0);  // a failed read leaves the frame alone
    EXPECT_TRUE(samePixels(frame.depth_raw, makeDepth(kSmall, 0)));
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.index, 2);
    EXPECT_TRUE(samePixels(frame.depth_raw, makeDepth(kSmall, 2)));
    EXPECT_FALSE(source.next(frame));
}

TEST(PpmPgmSource, ImageSizeMustMatchCalibration) {
    PpmPgmFolder folder({0});
    writePGM16(folder.dir.path() + "/depth/0000.pgm", makeDepth({5, 3}, 0));
    PpmPgmSource source(folder.rgbPattern(), folder.depthPattern(), folder.calib);
    RGBDFrame frame;
    try {
        source.next(frame);
        FAIL() << "expected IoError";
    } catch (const IoError& e) {
        EXPECT_TRUE(containsText(e.reason(), "depth image is 5x3 but the calibration's depth camera is 4x3"))
            << e.what();
    }
}

TEST(PpmPgmSource, RejectsBadPatterns) {
    PpmPgmFolder folder({0});
    for (const std::string pattern : {"/depth/%s.pgm", "/depth/0000.pgm", "/depth/%04i_%04i.pgm", "/depth/%ld.pgm",
                                      "/depth/%*d.pgm", "/depth/%04i%n.pgm", "/depth/%04f.pgm", "/depth/%"}) {
        SCOPED_TRACE(pattern);
        try {
            PpmPgmSource source("", folder.dir.path() + pattern, folder.calib);
            ADD_FAILURE() << "accepted";
        } catch (const ConfigError& e) {
            EXPECT_TRUE(containsText(e.what(), "depth pattern")) << e.what();
            EXPECT_TRUE(containsText(e.what(), pattern)) << e.what();
        }
    }
    EXPECT_THROW(PpmPgmSource("rgb/%s.ppm", folder.depthPattern(), folder.calib), ConfigError);
}

TEST(PpmPgmSource, LiteralPercentInPattern) {
    PpmPgmFolder folder({});
    writePGM16(folder.dir.file("100%_7.pgm"), makeDepth(kSmall, 7));
    PpmPgmSource source("", folder.dir.path() + "/100%%_%d.pgm", folder.calib, 7);
    EXPECT_EQ(source.frameCount(), 1);
}

TEST(PpmPgmSource, NoFirstFrameIsAnError) {
    PpmPgmFolder folder({});
    EXPECT_THROW(PpmPgmSource(folder.rgbPattern(), folder.depthPattern(), folder.calib), IoError);
}

TEST(PpmPgmSource, GroundTruthMatchedByCount) {
    PpmPgmFolder folder({0, 1, 2});
    writeBytes(folder.dir.file("depth/groundtruth.txt"), "5.0 0 0 0 0 0 0 1\n6.0 1 0 0 0 0 0 1\n7.0 2 0 0 0 0 0 1\n");
    PpmPgmSource source(folder.rgbPattern(), folder.depthPattern(), folder.calib);
    ASSERT_EQ(source.groundTruth().size(), 3u);
    EXPECT_DOUBLE_EQ(source.groundTruth()[2].timestamp_s, 2 / 30.0);  // restamped with the frames' times
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    ASSERT_TRUE(source.next(frame));
    EXPECT_TRUE(frame.has_ground_truth);
    EXPECT_FLOAT_EQ(frame.T_world_camera_gt(0, 3), 1.f);

    writeBytes(folder.dir.file("depth/groundtruth.txt"), "5.0 0 0 0 0 0 0 1\n");  // wrong count: ignored
    PpmPgmSource mismatched(folder.rgbPattern(), folder.depthPattern(), folder.calib);
    EXPECT_TRUE(mismatched.groundTruth().empty());
    ASSERT_TRUE(mismatched.next(frame));
    EXPECT_FALSE(frame.has_ground_truth);
}

// ----------------------------------------------------------------------------------------------
// Per-frame folders

TEST(FrameFolderSource, SortsByNumberAndScalesColorIntrinsics) {
    ScratchDir dir;
    const Vec2i color_size{8, 6};
    for (int number : {10, 3, 7}) {
        char stem[32];
        std::snprintf(stem, sizeof stem, "frame-%06d", number);
        writeDepthPNG(dir.file(std::string(stem) + ".depth.png"), makeDepth(kSmall, number));
        writePNG(dir.file(std::string(stem) + ".color.png"), makeRgb(color_size, number));
    }
    writeBytes(dir.file("frame-000003.pose.txt"), "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
    writeBytes(dir.file("frame-000007.pose.txt"), "1 0 0 0.5\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
    writeBytes(dir.file("frame-000010.pose.txt"),
               "-inf -inf -inf -inf\n-inf -inf -inf -inf\n-inf -inf -inf -inf\n0 0 0 1\n");
    writeBytes(dir.file("camera-intrinsics.txt"), "5 0 1.5\n0 6 1\n0 0 1\n");
    writeBytes(dir.file("frame-notanumber.depth.png"), "ignored");

    FrameFolderSource source(dir.path());
    EXPECT_EQ(source.frameCount(), 3);
    const RGBDCalib& calib = source.calib();
    EXPECT_EQ(calib.depth.size(), kSmall);
    EXPECT_FLOAT_EQ(calib.depth.fx, 5.f);
    EXPECT_FLOAT_EQ(calib.depth.fy, 6.f);
    EXPECT_EQ(calib.rgb.size(), color_size);
    EXPECT_FLOAT_EQ(calib.rgb.fx, 10.f);
    EXPECT_FLOAT_EQ(calib.rgb.cx, 3.5f);  // (1.5 + 0.5) * 2 - 0.5
    EXPECT_FLOAT_EQ(calib.disparity.a, 0.001f);
    ASSERT_EQ(source.groundTruth().size(), 2u);  // the -inf pose marks a lost frame
    EXPECT_DOUBLE_EQ(source.groundTruth()[1].timestamp_s, 7 / 30.0);

    RGBDFrame frame;
    const int numbers[] = {3, 7, 10};
    for (int i = 0; i < 3; ++i) {
        SCOPED_TRACE(i);
        ASSERT_TRUE(source.next(frame));
        EXPECT_EQ(frame.index, i);
        EXPECT_DOUBLE_EQ(frame.timestamp_s, numbers[i] / 30.0);
        EXPECT_TRUE(samePixels(frame.depth_raw, makeDepth(kSmall, numbers[i])));
        EXPECT_TRUE(samePixels(frame.rgb, makeRgb(color_size, numbers[i])));
        EXPECT_EQ(frame.has_ground_truth, numbers[i] != 10);
    }
    EXPECT_FALSE(source.next(frame));
}

TEST(FrameFolderSource, MissingIntrinsicsAndMalformedPoseAreErrors) {
    ScratchDir dir;
    writeDepthPNG(dir.file("frame-000001.depth.png"), makeDepth(kSmall, 1));
    EXPECT_THROW(FrameFolderSource source(dir.path()), IoError);

    writeBytes(dir.file("intrinsics.K.txt"), "5 0 1.5\n0 5 1\n0 0 1\n");
    writeBytes(dir.file("frame-000001.pose.txt"), "1 0 0 0\n0 1 0 0\n0 0 1\n0 0 0 1\n");
    try {
        FrameFolderSource source(dir.path());
        FAIL() << "expected ParseError";
    } catch (const ParseError& e) {
        EXPECT_EQ(e.line(), 3);
        EXPECT_TRUE(containsText(e.what(), "frame-000001.pose.txt:3")) << e.what();
    }
}

TEST(FrameFolderSource, PosesAreRotationsOrMarkedLost) {
    struct Case {
        const char* what;
        std::string pose;
        const char* reason_part;  // "" when the pose is accepted
    };
    const std::vector<Case> cases = {
        {"a scaled rotation", "2 0 0 0\n0 2 0 0\n0 0 2 0\n0 0 0 1\n", "is not a rotation"},
        {"a reflection", "-1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "reflection"},
        {"one non-finite value", "1 0 0 nan\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "non-finite values"},
        {"finite as a double, infinite as a float", "1 0 0 1e39\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "non-finite values"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.what);
        ScratchDir dir;
        writeDepthPNG(dir.file("frame-000001.depth.png"), makeDepth(kSmall, 1));
        writeBytes(dir.file("intrinsics.K.txt"), "5 0 1.5\n0 5 1\n0 0 1\n");
        writeBytes(dir.file("frame-000001.pose.txt"), c.pose);
        try {
            FrameFolderSource source(dir.path());
            ADD_FAILURE() << "accepted";
        } catch (const IoError& e) {
            EXPECT_TRUE(containsText(e.file(), "frame-000001.pose.txt")) << e.what();
            EXPECT_TRUE(containsText(e.reason(), c.reason_part)) << e.what();
        }
    }
    // Lost tracking marked with -inf is counted, and said.
    ScratchDir dir;
    writeDepthPNG(dir.file("frame-000001.depth.png"), makeDepth(kSmall, 1));
    writeBytes(dir.file("intrinsics.K.txt"), "5 0 1.5\n0 5 1\n0 0 1\n");
    writeBytes(dir.file("frame-000001.pose.txt"),
               "-inf -inf -inf -inf\n-inf -inf -inf -inf\n-inf -inf -inf -inf\n-inf -inf -inf -inf\n");
    FrameFolderSource source(dir.path());
    EXPECT_TRUE(source.groundTruth().empty());
    EXPECT_TRUE(containsText(source.description(), "1 whose pose files mark lost tracking")) << source.description();
}

TEST(FrameFolderSource, IntrinsicsAreCheckedAgainstTheImages) {
    ScratchDir dir;
    writeDepthPNG(dir.file("frame-000001.depth.png"), makeDepth(kSmall, 1));
    writeBytes(dir.file("intrinsics.K.txt"), "5 0 40\n0 5 1\n0 0 1\n");  // cx beyond the 4-pixel width
    try {
        FrameFolderSource source(dir.path());
        FAIL() << "accepted";
    } catch (const IoError& e) {
        EXPECT_TRUE(containsText(e.file(), "intrinsics.K.txt")) << e.what();
        EXPECT_TRUE(containsText(e.reason(), "principal point (40, 1) lies outside the 4x3 depth images")) << e.what();
    }
    writeBytes(dir.file("intrinsics.K.txt"), "1e39 0 1.5\n0 5 1\n0 0 1\n");
    try {
        FrameFolderSource source(dir.path());
        FAIL() << "accepted";
    } catch (const IoError& e) {
        EXPECT_TRUE(containsText(e.reason(), "non-finite value in K")) << e.what();
    }
}

TEST(TumSource, AGroundTruthWithTwoPosesForOneTimeIsRefused) {
    HandMadeTumFolder folder;
    writeBytes(folder.dir.file("groundtruth.txt"), "1.000 0 0 0 0 0 0 1\n1.000 1 0 0 0 0 0 1\n");
    try {
        TumSource source(folder.dir.path());
        FAIL() << "accepted";
    } catch (const ParseError& e) {
        EXPECT_EQ(e.line(), 2);
        EXPECT_TRUE(containsText(e.what(), "groundtruth.txt:2")) << e.what();
        EXPECT_TRUE(containsText(e.reason(), "given twice")) << e.what();
    }
}

// ----------------------------------------------------------------------------------------------
// openImageSource

TEST(OpenImageSource, PicksTheRightSource) {
    HandMadeTumFolder tum;
    EXPECT_TRUE(containsText(openImageSource(tum.dir.path())->description(), "TUM folder"));

    PpmPgmFolder ppm({0, 1});
    SourceOptions options;
    options.rgb_pattern = "rgb/%04i.ppm";  // relative to the path
    options.depth_pattern = "depth/%04i.pgm";
    options.calib_path = ppm.calib;
    const auto sequence = openImageSource(ppm.dir.path(), options);
    EXPECT_EQ(sequence->frameCount(), 2);
    EXPECT_TRUE(containsText(sequence->description(), "PPM/PGM sequence"));

    ScratchDir frames;
    writeDepthPNG(frames.file("frame-000000.depth.png"), makeDepth(kSmall, 0));
    writeBytes(frames.file("intrinsics.K.txt"), "5 0 1.5\n0 5 1\n0 0 1\n");
    EXPECT_TRUE(containsText(openImageSource(frames.path())->description(), "frame folder"));
}

TEST(OpenImageSource, ExplainsWhatIsAccepted) {
    auto expectReason = [](const std::string& path, const SourceOptions& options, const std::string& reason_part) {
        try {
            openImageSource(path, options);
            ADD_FAILURE() << "no IoError for " << path;
        } catch (const IoError& e) {
            EXPECT_EQ(e.file(), path);
            EXPECT_TRUE(containsText(e.reason(), reason_part)) << e.what();
        }
    };
    ScratchDir empty;
    expectReason(empty.path() + "/recording.oni", {},
                 OpenNISource::available() ? "no such file" : "OpenNI2 input is not available in this build");
    expectReason(empty.path(), {}, "not a known image source; expected one of: a TUM RGB-D folder");
    expectReason(empty.path() + "/nothing_here", {}, "no such file or folder");
    // RealSense input is the Python package's: the CLI and the library say where to go, file or not.
    for (const std::string& realsense :
         {empty.path() + "/walk.bag", empty.path() + "/walk.DB3", std::string("realsense:")})
        expectReason(realsense, {}, "python -m voxfuse " + realsense);
    SourceOptions no_calib;
    no_calib.depth_pattern = "%04i.pgm";
    expectReason(empty.path(), no_calib, "needs a calibration file");
}

// ----------------------------------------------------------------------------------------------
// The recorded data in ../shared/data

TEST(SharedData, TumTeddyPairsAndGroundTruth) {
    VOXFUSE_REQUIRE_SHARED_DATA("tum_fr3_teddy_200", folder);
    const auto source = openImageSource(folder);
    auto* tum = dynamic_cast<TumSource*>(source.get());
    ASSERT_NE(tum, nullptr);
    // 200 depth and 200 rgb PNGs on disk (the lists name the whole sequence); 193 depth frames have
    // an rgb image within 0.02 s: 2 in the middle lack one, and the last 5 depth frames come after
    // the last rgb image of the trimmed copy.
    EXPECT_EQ(source->frameCount(), 193);
    EXPECT_EQ(tum->droppedDepthFrames(), 7);
    EXPECT_FLOAT_EQ(source->calib().depth.fx, 535.4f);  // fr3 from the folder name
    EXPECT_FLOAT_EQ(source->calib().disparity.a, 0.0002f);
    EXPECT_GT(source->groundTruth().size(), 8000u);

    RGBDFrame frame;
    int frames = 0, first_with_gt = -1;
    while (source->next(frame)) {
        ASSERT_EQ(frame.depth_raw.size(), (Vec2i{640, 480}));
        ASSERT_EQ(frame.rgb.size(), (Vec2i{640, 480}));
        if (frame.has_ground_truth && first_with_gt < 0) first_with_gt = frame.index;
        if (first_with_gt >= 0) {
            EXPECT_TRUE(frame.has_ground_truth) << "frame " << frame.index;
        }
        ++frames;
    }
    EXPECT_EQ(frames, 193);
    EXPECT_EQ(first_with_gt, 4);  // motion capture starts 0.14 s into the recording
}

TEST(SharedData, KinfuSampleOpensWith50Frames) {
    VOXFUSE_REQUIRE_SHARED_DATA("kinfu_sample_50", folder);
    const auto source = openImageSource(folder);
    EXPECT_EQ(source->frameCount(), 50);
    EXPECT_NEAR(source->calib().depth.fx, 615.195f, 1e-3f);
    EXPECT_EQ(source->calib().depth.size(), (Vec2i{640, 480}));
    EXPECT_EQ(source->groundTruth().size(), 50u);

    RGBDFrame frame;
    ASSERT_TRUE(source->next(frame));
    EXPECT_DOUBLE_EQ(frame.timestamp_s, 15 / 30.0);
    ASSERT_TRUE(frame.has_ground_truth);
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) EXPECT_EQ(frame.T_world_camera_gt(r, c), r == c ? 1.f : 0.f);
    ASSERT_TRUE(source->next(frame));
    EXPECT_DOUBLE_EQ(frame.timestamp_s, 17 / 30.0);
    EXPECT_NEAR(frame.T_world_camera_gt(2, 3), 0.02183488f, 1e-7f);
    int frames = 2;
    while (source->next(frame)) ++frames;
    EXPECT_EQ(frames, 50);
    EXPECT_DOUBLE_EQ(frame.timestamp_s, 113 / 30.0);
}

}  // namespace
}  // namespace voxfuse
