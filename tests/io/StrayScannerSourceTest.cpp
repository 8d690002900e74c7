#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "IoTestUtil.h"
#include "Watchdog.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/ArkitPose.h"
#include "voxfuse/io/ImageIO.h"
#include "voxfuse/io/StrayScannerSource.h"
#include "voxfuse/io/ThreadedImageSource.h"

namespace voxfuse {
namespace {

using test::ScratchDir;
using test::writeBytes;

constexpr int kVideoWidth = 160, kVideoHeight = 120;  // 4:3 like the iPhone's 1920x1440
constexpr int kDepthWidth = 32, kDepthHeight = 24;    // 4:3 like the iPhone's 256x192

// Each frame's colour is uniform and different, so a frame shows which video frame it got.
Vec4u8 colorOf(int frame) { return Vec4u8{std::uint8_t(30 + 50 * frame), std::uint8_t(200 - 40 * frame), 90, 255}; }
// A tilted plane, in millimetres, moving 1 mm per frame.
std::uint16_t planeDepth(int x, int y, int frame) { return std::uint16_t(1000 + 10 * x + 5 * y + frame); }
std::uint8_t confidenceAt(int x, int y) { return std::uint8_t((x + y) % 3); }

struct Pose {
    double t;
    Vec3f position;
    Vec4f q;
};
const float kHalf = std::sqrt(0.5f);
const std::vector<Pose> kPoses = {{10.0, {0.f, 0.f, 0.f}, {0.f, 0.f, 0.f, 1.f}},
                                  {10.0167, {0.1f, 0.f, 0.f}, {0.f, 0.f, 0.f, 1.f}},
                                  {10.0333, {0.1f, 0.f, 0.f}, {0.f, kHalf, 0.f, kHalf}},
                                  {10.05, {0.f, 0.2f, -0.3f}, {0.1f, 0.2f, 0.3f, 0.9f}}};

// Writes a Stray Scanner capture of `frames` frames into a scratch folder.
struct StrayCapture {
    ScratchDir dir;
    int frames;

    explicit StrayCapture(int frame_count, const char* fourcc = "mp4v", int video_frames = -1,
                          cv::Size video_size = {kVideoWidth, kVideoHeight})
        : frames(frame_count) {
        for (int i = 0; i < frames; ++i) {
            Image<std::uint16_t> depth({kDepthWidth, kDepthHeight});
            cv::Mat confidence(kDepthHeight, kDepthWidth, CV_8UC1);
            for (int y = 0; y < kDepthHeight; ++y)
                for (int x = 0; x < kDepthWidth; ++x) {
                    depth.at(x, y) = planeDepth(x, y, i);
                    confidence.at<std::uint8_t>(y, x) = confidenceAt(x, y);
                }
            writeDepthPNG(dir.file(name("depth", i)), depth);
            cv::imwrite(dir.file(name("confidence", i)), confidence);
        }
        writeVideo(fourcc, video_frames < 0 ? frames : video_frames, video_size);
        // K at the video's full resolution, written as the app writes it.
        writeBytes(dir.file("camera_matrix.csv"), "130.0,0.0,79.5\n0.0,130.0,59.5\n0.0,0.0,1.0\n");
        std::string odometry = "timestamp, frame, x, y, z, qx, qy, qz, qw\n";
        for (int i = 0; i < frames && i < int(kPoses.size()); ++i) {
            const Pose& p = kPoses[std::size_t(i)];
            char line[256];
            std::snprintf(line, sizeof line, "%.4f, %06d, %g, %g, %g, %g, %g, %g, %g\n", p.t, i, p.position.x,
                          p.position.y, p.position.z, p.q.x, p.q.y, p.q.z, p.q.w);
            odometry += line;
        }
        writeBytes(dir.file("odometry.csv"), odometry);
        writeBytes(dir.file("imu.csv"), "timestamp, a_x, a_y, a_z, alpha_x, alpha_y, alpha_z\n");
    }

    static std::string name(const char* folder, int i) {
        char buffer[64];
        std::snprintf(buffer, sizeof buffer, "%s/%06d.png", folder, i);
        return buffer;
    }

    void writeVideo(const char* fourcc, int count, cv::Size size) {
        cv::VideoWriter writer(dir.file("rgb.mp4"), cv::CAP_FFMPEG,
                               cv::VideoWriter::fourcc(fourcc[0], fourcc[1], fourcc[2], fourcc[3]), 60.0, size);
        video_written = writer.isOpened();
        if (!video_written) return;
        for (int i = 0; i < count; ++i) {
            const Vec4u8 c = colorOf(i);
            writer.write(cv::Mat(size, CV_8UC3, cv::Scalar(c.z, c.y, c.x)));  // BGR
        }
    }

    std::string path() const { return dir.path(); }
    bool video_written = false;
};

SourceOptions colorWidth(int width) {
    SourceOptions options;
    options.max_color_width = width;
    return options;
}

void expectColorNear(const Image<Vec4u8>& rgb, Vec4u8 expected, int frame) {
    ASSERT_FALSE(rgb.empty());
    const Vec4u8 c = rgb.at(rgb.width() / 2, rgb.height() / 2);
    EXPECT_NEAR(c.x, expected.x, 12) << "frame " << frame;
    EXPECT_NEAR(c.y, expected.y, 12) << "frame " << frame;
    EXPECT_NEAR(c.z, expected.z, 12) << "frame " << frame;
}

template <typename Call>
void expectIoError(Call call, const std::string& file, const std::string& reason_part, int frame = -1) {
    try {
        call();
        ADD_FAILURE() << "no IoError (expected '" << reason_part << "')";
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), file) << e.what();
        EXPECT_NE(e.reason().find(reason_part), std::string::npos) << e.what();
        EXPECT_EQ(e.frame(), frame) << e.what();
    }
}

TEST(StrayScannerSource, ReadsFramesCalibrationAndArkitPoses) {
    StrayCapture capture(4);
    ASSERT_TRUE(capture.video_written) << "OpenCV cannot write mp4v here";
    StrayScannerSource source(capture.path(), colorWidth(80));
    EXPECT_EQ(source.frameCount(), 4);
    EXPECT_FALSE(source.isLive());

    // K of the 160x120 video, scaled to the 80x60 colour delivered and the 32x24 depth maps.
    const RGBDCalib& calib = source.calib();
    EXPECT_EQ(calib.rgb.size(), (Vec2i{80, 60}));
    EXPECT_FLOAT_EQ(calib.rgb.fx, 65.f);
    EXPECT_FLOAT_EQ(calib.rgb.cx, 39.5f);
    EXPECT_FLOAT_EQ(calib.rgb.cy, 29.5f);
    EXPECT_EQ(calib.depth.size(), (Vec2i{kDepthWidth, kDepthHeight}));
    EXPECT_FLOAT_EQ(calib.depth.fx, 26.f);
    EXPECT_FLOAT_EQ(calib.depth.fy, 26.f);
    EXPECT_FLOAT_EQ(calib.depth.cx, 15.5f);
    EXPECT_FLOAT_EQ(calib.depth.cy, 11.5f);
    EXPECT_FLOAT_EQ(calib.disparity.a, 0.001f);
    EXPECT_FLOAT_EQ(calib.T_depth_rgb(0, 3), 0.f);

    ASSERT_EQ(source.groundTruth().size(), 4u);
    RGBDFrame frame;
    for (int i = 0; i < 4; ++i) {
        ASSERT_TRUE(source.next(frame));
        EXPECT_EQ(frame.index, i);
        EXPECT_DOUBLE_EQ(frame.timestamp_s, kPoses[std::size_t(i)].t);
        ASSERT_EQ(frame.depth_raw.size(), (Vec2i{kDepthWidth, kDepthHeight}));
        for (int y = 0; y < kDepthHeight; ++y)
            for (int x = 0; x < kDepthWidth; ++x)  // low confidence (0) is dropped by default
                ASSERT_EQ(frame.depth_raw.at(x, y), confidenceAt(x, y) >= 1 ? planeDepth(x, y, i) : 0) << x << "," << y;
        EXPECT_EQ(frame.rgb.size(), (Vec2i{80, 60}));
        expectColorNear(frame.rgb, colorOf(i), i);
        ASSERT_TRUE(frame.has_ground_truth);
        const Pose& p = kPoses[std::size_t(i)];
        const Mat4f expected = poseFromArkit(p.position, p.q);
        for (int k = 0; k < 16; ++k) EXPECT_NEAR(frame.T_world_camera_gt.m[k], expected.m[k], 1e-5f) << "frame " << i;
        EXPECT_EQ(source.groundTruth()[std::size_t(i)].timestamp_s, frame.timestamp_s);
    }
    EXPECT_FALSE(source.next(frame));
    // Frame 1: moved 10 cm along ARKit's x, unrotated: our camera's axes y and z are flipped.
    const Mat4f& T1 = source.groundTruth()[1].T_world_camera;
    EXPECT_FLOAT_EQ(T1(0, 3), 0.1f);
    EXPECT_FLOAT_EQ(T1(1, 1), -1.f);
    EXPECT_FLOAT_EQ(T1(2, 2), -1.f);
}

TEST(StrayScannerSource, FullResolutionColorWhenTheWidthIsNotLimited) {
    StrayCapture capture(1);
    StrayScannerSource source(capture.path(), colorWidth(0));
    EXPECT_EQ(source.calib().rgb.size(), (Vec2i{kVideoWidth, kVideoHeight}));
    EXPECT_FLOAT_EQ(source.calib().rgb.fx, 130.f);
    EXPECT_FLOAT_EQ(source.calib().rgb.cx, 79.5f);
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.rgb.size(), (Vec2i{kVideoWidth, kVideoHeight}));
}

TEST(StrayScannerSource, ConfidenceThresholdChoosesWhichDepthSurvives) {
    StrayCapture capture(1);
    for (int threshold : {0, 2}) {
        SourceOptions options;
        options.min_depth_confidence = threshold;
        StrayScannerSource source(capture.path(), options);
        RGBDFrame frame;
        ASSERT_TRUE(source.next(frame));
        for (int y = 0; y < kDepthHeight; ++y)
            for (int x = 0; x < kDepthWidth; ++x)
                ASSERT_EQ(frame.depth_raw.at(x, y), confidenceAt(x, y) >= threshold ? planeDepth(x, y, 0) : 0);
    }
}

TEST(StrayScannerSource, AGapInTheDepthMapsTakesTheMatchingVideoFrame) {
    StrayCapture capture(4);
    std::filesystem::remove(capture.dir.file(StrayCapture::name("depth", 2)));
    StrayScannerSource source(capture.path());
    EXPECT_EQ(source.frameCount(), 3);
    RGBDFrame frame;
    for (int number : {0, 1, 3}) {
        ASSERT_TRUE(source.next(frame));
        expectColorNear(frame.rgb, colorOf(number), number);
        EXPECT_EQ(frame.depth_raw.at(0, 1), planeDepth(0, 1, number));
    }
}

TEST(StrayScannerSource, FramesPastTheEndOfTheVideoAreFrameErrors) {
    StrayCapture capture(4, "mp4v", 2);
    StrayScannerSource source(capture.path());
    const std::string video = capture.dir.file("rgb.mp4");
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    ASSERT_TRUE(source.next(frame));
    expectIoError([&] { source.next(frame); }, video, "the video ends before frame 2", 2);
    expectIoError([&] { source.next(frame); }, video, "the video ends before frame 3", 3);
    EXPECT_FALSE(source.next(frame));
}

TEST(StrayScannerSource, AMissingOrBrokenConfidenceMapIsThatFramesError) {
    StrayCapture capture(3);
    const std::string missing = capture.dir.file(StrayCapture::name("confidence", 1));
    std::filesystem::remove(missing);
    StrayScannerSource source(capture.path());
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    expectIoError([&] { source.next(frame); }, missing, "missing confidence map", 1);
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.index, 2);
    expectColorNear(frame.rgb, colorOf(2), 2);
}

TEST(StrayScannerSource, MissingPartsAreNamed) {
    {
        StrayCapture capture(1);
        std::filesystem::remove(capture.dir.file("rgb.mp4"));
        expectIoError([&] { StrayScannerSource source(capture.path()); }, capture.dir.file("rgb.mp4"), "no such file");
    }
    {
        StrayCapture capture(1);
        std::filesystem::remove(capture.dir.file("camera_matrix.csv"));
        expectIoError([&] { StrayScannerSource source(capture.path()); }, capture.dir.file("camera_matrix.csv"),
                      "cannot open");
    }
    {
        StrayCapture capture(1);
        std::filesystem::remove(capture.dir.file(StrayCapture::name("depth", 0)));
        expectIoError([&] { StrayScannerSource source(capture.path()); }, capture.dir.file("depth"), "no depth maps");
    }
    {
        StrayCapture capture(1);
        writeBytes(capture.dir.file("rgb.mp4"), "not a video at all");
        expectIoError([&] { StrayScannerSource source(capture.path()); }, capture.dir.file("rgb.mp4"),
                      "cannot open this video");
    }
}

TEST(StrayScannerSource, DepthAndVideoOfDifferentAspectRatiosAreRejected) {
    StrayCapture capture(1, "mp4v", -1, cv::Size(120, 160));  // a rotated video
    writeBytes(capture.dir.file("camera_matrix.csv"), "130,0,59.5\n0,130,79.5\n0,0,1\n");
    expectIoError([&] { StrayScannerSource source(capture.path()); }, capture.path(), "different aspect ratios");
}

TEST(StrayScannerSource, MalformedCsvLinesAreParseErrorsWithTheLine) {
    StrayCapture capture(2);
    const std::string odometry = capture.dir.file("odometry.csv");
    writeBytes(odometry, "timestamp, frame, x, y, z, qx, qy, qz, qw\n1.0, 0, 0, 0, 0, 0, 0, 0, 1\n1.1, 1, 0, 0\n");
    try {
        StrayScannerSource source(capture.path());
        ADD_FAILURE() << "no ParseError";
    } catch (const ParseError& e) {
        EXPECT_EQ(e.file(), odometry);
        EXPECT_EQ(e.line(), 3);
        EXPECT_NE(e.reason().find("expected 9 values, got 4"), std::string::npos) << e.what();
    }
    writeBytes(odometry, "timestamp, frame, x, y, z, qx, qy, qz, qw\n1.0, 0, 0, 0, 0, 0, 0, 0, 0\n");
    EXPECT_THROW(StrayScannerSource(capture.path()), ParseError);  // zero-length quaternion
    writeBytes(odometry, "time, x, y, z, qx, qy, qz, qw\n");
    EXPECT_THROW(StrayScannerSource(capture.path()), ParseError);  // no timestamp column
    writeBytes(capture.dir.file("camera_matrix.csv"), "130,0,79.5\n0,130\n0,0,1\n");
    EXPECT_THROW(StrayScannerSource(capture.path()), ParseError);
}

TEST(StrayScannerSource, OdometryValuesAreCheckedAsFloatsAndOneFrameHasOnePose) {
    StrayCapture capture(2);
    const std::string odometry = capture.dir.file("odometry.csv");
    const std::string header = "timestamp, frame, x, y, z, qx, qy, qz, qw\n";
    struct Case {
        const char* what;
        std::string rows;
        int line;
        const char* reason_part;
    };
    const std::vector<Case> cases = {
        {"position finite as a double, infinite as a float", "1.0, 0, 1e39, 0, 0, 0, 0, 0, 1\n", 2,
         "non-finite value '1e39'"},
        {"one frame, two poses", "1.0, 0, 0, 0, 0, 0, 0, 0, 1\n1.1, 0, 0.5, 0, 0, 0, 0, 0, 1\n", 3,
         "frame 0 is given twice, differently (line 2"},
        {"one time, two poses", "1.0, 0, 0, 0, 0, 0, 0, 0, 1\n1.0, 1, 0.5, 0, 0, 0, 0, 0, 1\n", 3,
         "timestamp 1.0 is given twice"},
        {"a folder for the file", "", 0, "is a folder, not a file"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.what);
        std::filesystem::remove_all(odometry);
        if (c.line == 0)
            std::filesystem::create_directory(odometry);
        else
            writeBytes(odometry, header + c.rows);
        try {
            StrayScannerSource source(capture.path());
            ADD_FAILURE() << "accepted";
        } catch (const IoError& e) {
            EXPECT_EQ(e.file(), odometry) << e.what();
            if (c.line > 0) {
                EXPECT_NE(std::string(e.what()).find(odometry + ":" + std::to_string(c.line)), std::string::npos)
                    << e.what();
            }
            EXPECT_NE(e.reason().find(c.reason_part), std::string::npos) << e.what();
        }
    }
    std::filesystem::remove_all(odometry);
    writeBytes(
        odometry,
        header + "1.0, 0, 0, 0, 0, 0, 0, 0, 1\n1.0, 0, 0, 0, 0, 0, 0, 0, 1\n");  // the same row twice is harmless
    EXPECT_EQ(StrayScannerSource(capture.path()).groundTruth().size(), 1u);
}

TEST(StrayScannerSource, OdometryColumnsAreFoundByName) {
    StrayCapture capture(2);
    // Columns reordered, no frame column: row i belongs to frame i.
    writeBytes(capture.dir.file("odometry.csv"),
               "qw,qx,qy,qz,x,y,z,timestamp\n1,0,0,0,0,0,0,5.0\n1,0,0,0,0.5,0,0,5.5\n");
    StrayScannerSource source(capture.path());
    ASSERT_EQ(source.groundTruth().size(), 2u);
    EXPECT_DOUBLE_EQ(source.groundTruth()[1].timestamp_s, 5.5);
    EXPECT_FLOAT_EQ(source.groundTruth()[1].T_world_camera(0, 3), 0.5f);
}

TEST(StrayScannerSource, FramesWithoutOdometryHaveNoGroundTruth) {
    StrayCapture capture(3);
    writeBytes(capture.dir.file("odometry.csv"),
               "timestamp, frame, x, y, z, qx, qy, qz, qw\n2.0, 1, 0, 0, 0, 0, 0, 0, 1\n");
    StrayScannerSource source(capture.path());
    EXPECT_EQ(source.groundTruth().size(), 1u);
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    EXPECT_FALSE(frame.has_ground_truth);
    // On the odometry's clock: a frame before its nearest row at the video's 60 Hz, not frame 0 / 60 Hz
    // (thousands of seconds from its neighbours in a real capture).
    EXPECT_NEAR(frame.timestamp_s, 2.0 - 1.0 / 60.0, 1e-9);
    ASSERT_TRUE(source.next(frame));
    EXPECT_TRUE(frame.has_ground_truth);
    EXPECT_DOUBLE_EQ(frame.timestamp_s, 2.0);
    ASSERT_TRUE(source.next(frame));
    EXPECT_FALSE(frame.has_ground_truth);
    EXPECT_NEAR(frame.timestamp_s, 2.0 + 1.0 / 60.0, 1e-9);
}

TEST(StrayScannerSource, OpenImageSourceRecognisesACaptureAndTheInputThreadReadsIt) {
    test::Watchdog watchdog(std::chrono::seconds(60), "StrayScanner through ThreadedImageSource");
    StrayCapture capture(4);
    ASSERT_TRUE(StrayScannerSource::isCapture(capture.path()));
    auto source = openImageSource(capture.path());
    EXPECT_NE(source->description().find("Stray Scanner capture"), std::string::npos) << source->description();
    ThreadedImageSource threaded(std::move(source));
    RGBDFrame frame;
    int count = 0;
    while (threaded.next(frame)) {
        EXPECT_EQ(frame.index, count);
        expectColorNear(frame.rgb, colorOf(count), count);
        ++count;
    }
    EXPECT_EQ(count, 4);
}

// The app records HEVC (older versions H.264): both must decode with the OpenCV this project builds on.
TEST(StrayScannerSource, DecodesH264AndHevcVideos) {
    for (const char* fourcc : {"avc1", "hvc1"}) {
        StrayCapture capture(3, fourcc);
        if (!capture.video_written) {
            std::printf("[  SKIPPED ] no %s encoder in this OpenCV/FFmpeg: decoding not tested\n", fourcc);
            continue;
        }
        StrayScannerSource source(capture.path());
        RGBDFrame frame;
        for (int i = 0; i < 3; ++i) {
            ASSERT_TRUE(source.next(frame)) << fourcc;
            expectColorNear(frame.rgb, colorOf(i), i);
        }
    }
}

}  // namespace
}  // namespace voxfuse
