// OpenNISource without a camera or recording at hand: every failure is a clear IoError, never a
// crash or a hang. (Playback of a real recording: OniPlaybackTest.cpp, with the shared data.)

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <memory>
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
using test::ScratchDir;
using test::Watchdog;

const char* const kNotBuilt = "OpenNI2 input is not available in this build";

template <typename Call>
IoError expectIoError(Call call) {
    try {
        call();
    } catch (const IoError& e) {
        return e;
    }
    ADD_FAILURE() << "no IoError";
    return IoError("", "");
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(OpenNISource, AMissingRecordingIsNamed) {
    Watchdog watchdog(60s, "AMissingRecordingIsNamed");
    ScratchDir dir;
    const std::string path = dir.path() + "/missing.oni";
    for (bool through_open_image_source : {false, true}) {
        const IoError e = expectIoError([&] {
            if (through_open_image_source)
                openImageSource(path);
            else
                OpenNISource::openFile(path);
        });
        EXPECT_EQ(e.file(), path);
        EXPECT_TRUE(contains(e.reason(), OpenNISource::available() ? "no such file" : kNotBuilt)) << e.what();
    }
}

TEST(OpenNISource, AFileThatIsNoRecordingIsAClearError) {
    Watchdog watchdog(60s, "AFileThatIsNoRecordingIsAClearError");
    ScratchDir dir;
    for (const std::string& bytes :
         {std::string(), std::string("NI10 but nothing after the magic"), std::string(4096, '\x5a')}) {
        const std::string path = dir.file("bad.oni");
        test::writeBytes(path, bytes);
        const IoError e = expectIoError([&] { openImageSource(path); });
        EXPECT_EQ(e.file(), path);
        EXPECT_TRUE(contains(e.reason(), OpenNISource::available() ? "OpenNI2 cannot play this file" : kNotBuilt))
            << e.what();
    }
}

TEST(OpenNISource, NoCameraIsAClearErrorNotAHang) {
    Watchdog watchdog(60s, "NoCameraIsAClearErrorNotAHang");
    if (!OpenNISource::deviceUris().empty())
        GTEST_SKIP() << "a camera is connected: the no-camera error cannot be shown";
    const IoError e = expectIoError([] { OpenNISource::openDevice(); });
    EXPECT_EQ(e.file(), "OpenNI2 camera");
    EXPECT_TRUE(contains(e.reason(), OpenNISource::available() ? "no OpenNI2 camera found" : kNotBuilt)) << e.what();

    const IoError by_uri = expectIoError([] { OpenNISource::openDevice("1d27/0601@3/7"); });
    EXPECT_EQ(by_uri.file(), "1d27/0601@3/7");
}

// OpenNI2 ships a sample driver with a simulated camera, opened by the URI "Dummy": 320x240 depth
// (its top row 2000 mm) and colour at about 30 Hz. It stands in for a camera here.
std::unique_ptr<OpenNISource> openDummyCamera() {
    if (!OpenNISource::available()) return nullptr;
    try {
        return OpenNISource::openDevice("Dummy");
    } catch (const IoError& e) {
        std::printf("OpenNI2's Dummy driver is not installed (%s)\n", e.what());
        return nullptr;
    }
}

TEST(OpenNISource, ALiveCameraStreamsDepthWithTheNearestColor) {
    Watchdog watchdog(60s, "ALiveCameraStreamsDepthWithTheNearestColor");
    auto camera = openDummyCamera();
    if (!camera) GTEST_SKIP() << "no OpenNI2 or no Dummy driver";
    EXPECT_TRUE(camera->isLive());
    EXPECT_EQ(camera->frameCount(), -1);
    EXPECT_EQ(camera->calib().depth.size(), (Vec2i{320, 240}));
    EXPECT_FLOAT_EQ(camera->calib().depth.fx, 262.5f);  // Kinect defaults: the driver reports no field of view
    EXPECT_NE(camera->description().find("OpenNI2 camera Dummy"), std::string::npos) << camera->description();
    RGBDFrame frame;
    double previous = -1.0;
    int with_color = 0;
    for (int i = 0; i < 6; ++i) {
        ASSERT_TRUE(camera->next(frame));
        EXPECT_EQ(frame.index, i);
        ASSERT_EQ(frame.depth_raw.size(), (Vec2i{320, 240}));
        EXPECT_EQ(frame.depth_raw.at(100, 0), 2000);
        EXPECT_GT(frame.timestamp_s, previous);
        previous = frame.timestamp_s;
        if (!frame.rgb.empty()) {
            EXPECT_EQ(frame.rgb.size(), (Vec2i{320, 240}));
            ++with_color;
        }
    }
    EXPECT_GE(with_color, 4);  // the first depth frame may come before any colour
}

TEST(OpenNISource, ALiveCameraDropsFramesWhenTheEngineLagsAndStopsCleanly) {
    Watchdog watchdog(60s, "ALiveCameraDropsFramesWhenTheEngineLagsAndStopsCleanly");
    auto camera = openDummyCamera();
    if (!camera) GTEST_SKIP() << "no OpenNI2 or no Dummy driver";
    ThreadedSourceOptions options;
    options.queue_capacity = 2;
    ThreadedImageSource source(std::move(camera), options);
    RGBDFrame frame;
    int previous = -1;
    for (int i = 0; i < 6; ++i) {
        ASSERT_TRUE(source.next(frame));
        EXPECT_GT(frame.index, previous);  // newer frames, some skipped
        previous = frame.index;
        std::this_thread::sleep_for(100ms);  // an engine at 10 Hz behind a 30 Hz camera
    }
    EXPECT_GT(source.droppedFrames(), 0);
}

TEST(OpenNISource, OpeningAndFailingRepeatedlyKeepsWorking) {
    // OpenNI2 is initialised and shut down with the sources that use it; doing so again and again
    // must neither leak nor break it.
    Watchdog watchdog(120s, "OpeningAndFailingRepeatedlyKeepsWorking");
    ScratchDir dir;
    const std::string path = dir.file("bad.oni");
    test::writeBytes(path, "not a recording");
    for (int i = 0; i < 5; ++i) EXPECT_THROW(OpenNISource::openFile(path), IoError);
}

}  // namespace
}  // namespace voxfuse
