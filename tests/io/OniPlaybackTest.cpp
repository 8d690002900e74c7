// Playback of a real Kinect recording from ../shared/data/oni/test.oni: an OpenNI 1.x file (version
// 1.0.1.0) with 12 depth frames (codec 16zT) and 12 JPEG colour frames, 640x480.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "IoTestUtil.h"
#include "Watchdog.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/ImageSource.h"
#include "voxfuse/io/OpenNISource.h"
#include "voxfuse/io/ThreadedImageSource.h"

namespace voxfuse {
namespace {

using namespace std::chrono_literals;

struct FrameStats {
    double valid_fraction = 0.0;
    double mean_depth_m = 0.0;
    double mean_intensity = 0.0;
};

FrameStats statsOf(const RGBDFrame& frame, const RGBDCalib& calib) {
    FrameStats s;
    std::size_t valid = 0;
    double sum = 0.0;
    for (std::size_t i = 0; i < frame.depth_raw.pixelCount(); ++i) {
        const float d = calib.disparity.toMetres(frame.depth_raw.host()[i], calib.depth.fx);
        if (d <= 0.f) continue;
        ++valid;
        sum += d;
    }
    s.valid_fraction = double(valid) / double(frame.depth_raw.pixelCount());
    s.mean_depth_m = valid ? sum / double(valid) : 0.0;
    double intensity = 0.0;
    for (std::size_t i = 0; i < frame.rgb.pixelCount(); ++i) {
        const Vec4u8 c = frame.rgb.host()[i];
        intensity += (c.x + c.y + c.z) / 3.0;
    }
    s.mean_intensity = frame.rgb.empty() ? 0.0 : intensity / double(frame.rgb.pixelCount());
    return s;
}

TEST(OniPlayback, EveryFrameOfBothStreamsOfTheKinectRecording) {
    VOXFUSE_REQUIRE_SHARED_DATA("oni", folder);
    const std::string path = folder + "/test.oni";
    if (!OpenNISource::available()) {
        EXPECT_THROW(openImageSource(path), IoError);
        GTEST_SKIP() << "built without OpenNI2: only the error is checked";
    }
    test::Watchdog watchdog(120s, "test.oni playback");
    const auto source = openImageSource(path);
    EXPECT_FALSE(source->isLive());
    EXPECT_EQ(source->frameCount(), 12);
    const std::string description = source->description();
    EXPECT_NE(description.find("12 depth and 12 colour frames"), std::string::npos) << description;
    EXPECT_NE(description.find("mirrored frames flipped back"), std::string::npos) << description;

    // Registered depth, Kinect v1 defaults: the recording reports no colour field of view.
    const RGBDCalib& calib = source->calib();
    EXPECT_EQ(calib.depth.size(), (Vec2i{640, 480}));
    EXPECT_EQ(calib.rgb.size(), (Vec2i{640, 480}));
    EXPECT_FLOAT_EQ(calib.rgb.fx, 525.f);
    EXPECT_FLOAT_EQ(calib.depth.fx, 525.f);
    EXPECT_FLOAT_EQ(calib.depth.cx, 319.5f);
    EXPECT_FLOAT_EQ(calib.disparity.a, 0.001f);  // millimetres

    RGBDFrame frame;
    int count = 0;
    double previous_time = -1.0;
    while (source->next(frame)) {
        SCOPED_TRACE("frame " + std::to_string(count));
        EXPECT_EQ(frame.index, count);
        ASSERT_EQ(frame.depth_raw.size(), (Vec2i{640, 480}));
        ASSERT_EQ(frame.rgb.size(), (Vec2i{640, 480}));
        const FrameStats s = statsOf(frame, calib);
        // An indoor room seen by a Kinect: most pixels measured, 0.6-4.6 m, about 2.6 m on average.
        EXPECT_GT(s.valid_fraction, 0.7);
        EXPECT_GT(s.mean_depth_m, 2.0);
        EXPECT_LT(s.mean_depth_m, 3.2);
        std::uint16_t nearest = 65535, farthest = 0;
        for (std::size_t i = 0; i < frame.depth_raw.pixelCount(); ++i) {
            const std::uint16_t d = frame.depth_raw.host()[i];
            if (d == 0) continue;
            nearest = std::min(nearest, d);
            farthest = std::max(farthest, d);
        }
        EXPECT_GE(nearest, 500);
        EXPECT_LE(farthest, 10000);         // the sensor's maximum
        EXPECT_GT(s.mean_intensity, 30.0);  // a lit room, not a black or garbage image
        // 30 Hz, every frame (no skipping), increasing.
        if (previous_time >= 0.0) {
            EXPECT_NEAR(frame.timestamp_s - previous_time, 1.0 / 30.0, 0.005);
        }
        previous_time = frame.timestamp_s;
        ++count;
    }
    EXPECT_EQ(count, 12);
    EXPECT_FALSE(source->next(frame));  // stays at the end: no repeat, no wait
}

TEST(OniPlayback, ThroughTheInputThreadNoFrameIsLost) {
    VOXFUSE_REQUIRE_SHARED_DATA("oni", folder);
    if (!OpenNISource::available()) GTEST_SKIP() << "built without OpenNI2";
    test::Watchdog watchdog(120s, "test.oni through ThreadedImageSource");
    ThreadedSourceOptions options;
    options.queue_capacity = 2;
    ThreadedImageSource source(OpenNISource::openFile(folder + "/test.oni"), options);
    RGBDFrame frame;
    int count = 0;
    while (source.next(frame)) {
        EXPECT_EQ(frame.index, count++);
        std::this_thread::sleep_for(20ms);  // a slow engine
    }
    EXPECT_EQ(count, 12);
    EXPECT_EQ(source.droppedFrames(), 0);
}

TEST(OniPlayback, ATruncatedRecordingIsAClearError) {
    VOXFUSE_REQUIRE_SHARED_DATA("oni", folder);
    test::Watchdog watchdog(120s, "truncated test.oni");
    test::ScratchDir dir;
    const std::string truncated = dir.file("truncated.oni");
    {
        std::ifstream in(folder + "/test.oni", std::ios::binary);
        std::string bytes(1000000, '\0');
        in.read(&bytes[0], std::streamsize(bytes.size()));
        test::writeBytes(truncated, bytes);
    }
    try {
        const auto source = openImageSource(truncated);
        ADD_FAILURE() << "opened a truncated recording: " << source->description();
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), truncated);
        EXPECT_NE(e.reason().find(OpenNISource::available() ? "truncated" : "not available in this build"),
                  std::string::npos)
            << e.what();
    }
}

}  // namespace
}  // namespace voxfuse
