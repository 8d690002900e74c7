#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "Watchdog.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/FrameUndistorter.h"
#include "voxfuse/io/ThreadedImageSource.h"
#include "voxfuse/io/UndistortedImageSource.h"

namespace voxfuse {
namespace {

using namespace std::chrono_literals;
using test::Watchdog;

// What a ScriptedSource has done so far, observable from the test thread.
struct Progress {
    std::mutex mutex;
    std::condition_variable changed;
    int produced = 0;  // next() calls that returned a frame
    bool finished = false;

    void waitUntil(const std::function<bool()>& condition) {
        std::unique_lock<std::mutex> lock(mutex);
        ASSERT_TRUE(changed.wait_for(lock, 10s, condition)) << "the reader thread made no progress";
    }
};

struct Script {
    int frames = 10;
    std::set<int> bad_frames;  // throw IoError for these
    int fatal_frame = -1;      // throw std::runtime_error here
    bool live = false;
    std::chrono::milliseconds delay{0};  // per next() call, like a camera's frame interval
    LensDistortion depth_distortion;
};

// Frame i is a depth image filled with i + 1.
class ScriptedSource : public ImageSource {
public:
    static constexpr int kSize = 8;

    ScriptedSource(Script script, std::shared_ptr<Progress> progress)
        : script_(std::move(script)), progress_(std::move(progress)) {
        calib_.depth = Intrinsics{kSize, kSize, 10.f, 10.f, 3.5f, 3.5f};
        calib_.rgb = calib_.depth;
        calib_.depth_distortion = script_.depth_distortion;
        ground_truth_.push_back(TimedPose{0.5, Mat4f::identity()});
    }
    const RGBDCalib& calib() const override { return calib_; }
    bool next(RGBDFrame& frame) override {
        if (script_.delay.count() > 0) std::this_thread::sleep_for(script_.delay);
        if (position_ >= script_.frames) {
            std::lock_guard<std::mutex> lock(progress_->mutex);
            progress_->finished = true;
            progress_->changed.notify_all();
            return false;
        }
        const int index = position_++;
        if (script_.bad_frames.count(index)) throw IoError("scripted", "unreadable frame", index);
        if (index == script_.fatal_frame) throw std::runtime_error("device lost");
        frame.index = index;
        frame.depth_raw.resize({kSize, kSize});
        for (std::size_t i = 0; i < frame.depth_raw.pixelCount(); ++i)
            frame.depth_raw.host()[i] = std::uint16_t(index + 1);
        std::lock_guard<std::mutex> lock(progress_->mutex);
        ++progress_->produced;
        progress_->changed.notify_all();
        return true;
    }
    int frameCount() const override { return script_.frames; }
    std::string description() const override { return "scripted source"; }
    const std::vector<TimedPose>& groundTruth() const override { return ground_truth_; }
    bool isLive() const override { return script_.live; }

private:
    Script script_;
    std::shared_ptr<Progress> progress_;
    RGBDCalib calib_;
    std::vector<TimedPose> ground_truth_;
    int position_ = 0;
};

std::unique_ptr<ThreadedImageSource> threaded(const Script& script, std::shared_ptr<Progress> progress,
                                              ThreadedSourceOptions options = {}) {
    return std::make_unique<ThreadedImageSource>(std::make_unique<ScriptedSource>(script, std::move(progress)),
                                                 options);
}

ThreadedSourceOptions capacity(int n) {
    ThreadedSourceOptions options;
    options.queue_capacity = n;
    return options;
}

TEST(ThreadedImageSource, DeliversEveryFrameOfARecordingInOrder) {
    Watchdog watchdog(30s, "DeliversEveryFrameOfARecordingInOrder");
    auto progress = std::make_shared<Progress>();
    Script script;
    script.frames = 200;
    auto source = threaded(script, progress, capacity(3));
    EXPECT_FALSE(source->isLive());
    RGBDFrame frame;
    for (int i = 0; i < 200; ++i) {
        if (i % 17 == 0) std::this_thread::sleep_for(2ms);  // a slow engine: the reader must wait, not drop
        ASSERT_TRUE(source->next(frame)) << "frame " << i;
        EXPECT_EQ(frame.index, i);
        EXPECT_EQ(frame.depth_raw.at(3, 3), std::uint16_t(i + 1));
    }
    EXPECT_FALSE(source->next(frame));
    EXPECT_FALSE(source->next(frame));  // stays at the end
    EXPECT_EQ(source->droppedFrames(), 0);
}

TEST(ThreadedImageSource, ReaderRunsAheadUntilTheQueueIsFullThenWaits) {
    Watchdog watchdog(30s, "ReaderRunsAheadUntilTheQueueIsFullThenWaits");
    auto progress = std::make_shared<Progress>();
    Script script;
    script.frames = 100;
    auto source = threaded(script, progress, capacity(4));
    // Four frames fill the queue; the reader holds a fifth while it waits for room.
    progress->waitUntil([&] { return progress->produced >= 5; });
    std::this_thread::sleep_for(100ms);
    {
        std::lock_guard<std::mutex> lock(progress->mutex);
        EXPECT_EQ(progress->produced, 5);
    }
    RGBDFrame frame;
    ASSERT_TRUE(source->next(frame));
    EXPECT_EQ(frame.index, 0);
    progress->waitUntil([&] { return progress->produced >= 6; });  // one taken, one more read
}

TEST(ThreadedImageSource, LiveSourceDropsTheOldestFramesWhenTheEngineLags) {
    Watchdog watchdog(30s, "LiveSourceDropsTheOldestFramesWhenTheEngineLags");
    auto progress = std::make_shared<Progress>();
    Script script;
    script.frames = 50;
    script.live = true;
    auto source = threaded(script, progress, capacity(4));
    EXPECT_TRUE(source->isLive());
    progress->waitUntil([&] { return progress->finished; });  // the camera ran on without the engine
    RGBDFrame frame;
    for (int expected = 46; expected < 50; ++expected) {  // the newest four survive
        ASSERT_TRUE(source->next(frame));
        EXPECT_EQ(frame.index, expected);
    }
    EXPECT_FALSE(source->next(frame));
    EXPECT_EQ(source->droppedFrames(), 46);
    EXPECT_NE(source->description().find("dropping"), std::string::npos) << source->description();
}

TEST(ThreadedImageSource, WaitPolicyKeepsEveryFrameOfALiveSource) {
    Watchdog watchdog(30s, "WaitPolicyKeepsEveryFrameOfALiveSource");
    auto progress = std::make_shared<Progress>();
    Script script;
    script.frames = 50;
    script.live = true;
    ThreadedSourceOptions options = capacity(2);
    options.when_full = ThreadedSourceOptions::WhenFull::Wait;
    auto source = threaded(script, progress, options);
    RGBDFrame frame;
    int count = 0;
    while (source->next(frame)) EXPECT_EQ(frame.index, count++);
    EXPECT_EQ(count, 50);
    EXPECT_EQ(source->droppedFrames(), 0);
}

TEST(ThreadedImageSource, DropPolicyAppliesToRecordingsWhenAskedFor) {
    Watchdog watchdog(30s, "DropPolicyAppliesToRecordingsWhenAskedFor");
    auto progress = std::make_shared<Progress>();
    Script script;
    script.frames = 20;
    ThreadedSourceOptions options = capacity(5);
    options.when_full = ThreadedSourceOptions::WhenFull::DropOldest;
    auto source = threaded(script, progress, options);
    progress->waitUntil([&] { return progress->finished; });
    RGBDFrame frame;
    int count = 0;
    while (source->next(frame)) ++count;
    EXPECT_EQ(count, 5);
    EXPECT_EQ(source->droppedFrames(), 15);
}

TEST(ThreadedImageSource, ABadFrameThrowsAtItsPlaceAndTheSequenceGoesOn) {
    Watchdog watchdog(30s, "ABadFrameThrowsAtItsPlaceAndTheSequenceGoesOn");
    auto progress = std::make_shared<Progress>();
    Script script;
    script.frames = 10;
    script.bad_frames = {3, 7};
    auto source = threaded(script, progress, capacity(2));
    RGBDFrame frame;
    std::vector<int> seen;
    for (int call = 0; call < 20; ++call) {
        try {
            if (!source->next(frame)) break;
            seen.push_back(frame.index);
        } catch (const IoError& e) {
            EXPECT_EQ(e.file(), "scripted");
            seen.push_back(-e.frame());  // marks where the error arrived
        }
    }
    EXPECT_EQ(seen, (std::vector<int>{0, 1, 2, -3, 4, 5, 6, -7, 8, 9}));
}

TEST(ThreadedImageSource, AnyOtherExceptionArrivesAtItsPlaceAndEndsTheSequence) {
    Watchdog watchdog(30s, "AnyOtherExceptionArrivesAtItsPlaceAndEndsTheSequence");
    auto progress = std::make_shared<Progress>();
    Script script;
    script.frames = 10;
    script.fatal_frame = 5;
    auto source = threaded(script, progress);
    RGBDFrame frame;
    for (int i = 0; i < 5; ++i) {
        ASSERT_TRUE(source->next(frame));
        EXPECT_EQ(frame.index, i);
    }
    EXPECT_THROW(source->next(frame), std::runtime_error);
    EXPECT_FALSE(source->next(frame));
    EXPECT_FALSE(source->next(frame));
}

TEST(ThreadedImageSource, DestructionMidStreamDoesNotHang) {
    Watchdog watchdog(30s, "DestructionMidStreamDoesNotHang");
    for (int frames_read : {0, 3}) {
        auto progress = std::make_shared<Progress>();
        Script script;
        script.frames = 100000;
        auto source = threaded(script, progress, capacity(2));
        RGBDFrame frame;
        for (int i = 0; i < frames_read; ++i) ASSERT_TRUE(source->next(frame));
        progress->waitUntil([&] { return progress->produced >= frames_read + 3; });  // the reader waits for room
        source.reset();  // must release the waiting reader and join it
    }
}

TEST(ThreadedImageSource, DestructionWhileTheReaderWaitsForACameraDoesNotHang) {
    Watchdog watchdog(30s, "DestructionWhileTheReaderWaitsForACameraDoesNotHang");
    auto progress = std::make_shared<Progress>();
    Script script;
    script.frames = 1000;
    script.live = true;
    script.delay = 30ms;
    auto source = threaded(script, progress, capacity(2));
    RGBDFrame frame;
    ASSERT_TRUE(source->next(frame));
    const auto start = std::chrono::steady_clock::now();
    source.reset();  // the reader is inside next(): joins once that call returns
    EXPECT_LT(std::chrono::steady_clock::now() - start, 2s);
}

TEST(ThreadedImageSource, WaitForFrameSaysWhetherNextReturnsAtOnce) {
    // A camera with 300 ms between frames: a 10 ms wait finds nothing at first, a longer one the
    // frame; after the last frame the end counts as ready too.
    Watchdog watchdog(30s, "WaitForFrameSaysWhetherNextReturnsAtOnce");
    auto progress = std::make_shared<Progress>();
    Script script;
    script.frames = 1;
    script.delay = 300ms;
    auto source = threaded(script, progress, capacity(2));
    EXPECT_FALSE(source->waitForFrame(10ms)) << "the first frame takes 300 ms";
    EXPECT_TRUE(source->waitForFrame(5s));
    RGBDFrame frame;
    ASSERT_TRUE(source->next(frame));
    EXPECT_TRUE(source->waitForFrame(5s)) << "the end mark";
    EXPECT_FALSE(source->next(frame));
    EXPECT_TRUE(source->waitForFrame(0ms)) << "ended: next() returns false at once";
}

TEST(ThreadedImageSource, PassesTheSourcePropertiesThrough) {
    auto progress = std::make_shared<Progress>();
    Script script;
    script.frames = 7;
    auto source = threaded(script, progress);
    EXPECT_EQ(source->frameCount(), 7);
    ASSERT_EQ(source->groundTruth().size(), 1u);
    EXPECT_EQ(source->groundTruth()[0].timestamp_s, 0.5);
    EXPECT_EQ(source->calib().depth.width, ScriptedSource::kSize);
    EXPECT_NE(source->description().find("scripted source"), std::string::npos);
    EXPECT_NE(source->description().find("lossless"), std::string::npos);
}

TEST(ThreadedImageSource, RejectsAnEmptyQueueOrNoSource) {
    auto progress = std::make_shared<Progress>();
    EXPECT_THROW(threaded(Script{}, progress, capacity(0)), ConfigError);
    EXPECT_THROW(ThreadedImageSource(nullptr), ConfigError);
}

TEST(ThreadedImageSource, UndistortsOnTheReaderThreadWithTheCalibrationsCoefficients) {
    Watchdog watchdog(30s, "UndistortsOnTheReaderThreadWithTheCalibrationsCoefficients");
    Script script;
    script.frames = 3;
    script.depth_distortion = LensDistortion{1.0f, 0.f, 0.f, 0.f, 0.f};  // strong pincushion

    auto progress = std::make_shared<Progress>();
    auto source = threaded(script, progress);
    EXPECT_FALSE(source->calib().depth_distortion.any());  // frames come out undistorted
    EXPECT_NE(source->description().find("undistorting"), std::string::npos);

    // The same frames undistorted directly, for comparison.
    auto reference_progress = std::make_shared<Progress>();
    ScriptedSource reference(script, reference_progress);
    const FrameUndistorter undistorter(reference.calib());
    RGBDFrame frame, expected;
    for (int i = 0; i < 3; ++i) {
        ASSERT_TRUE(source->next(frame));
        ASSERT_TRUE(reference.next(expected));
        undistorter.apply(expected);
        ASSERT_EQ(frame.depth_raw.size(), expected.depth_raw.size());
        for (std::size_t p = 0; p < frame.depth_raw.pixelCount(); ++p)
            EXPECT_EQ(frame.depth_raw.host()[p], expected.depth_raw.host()[p]) << "frame " << i << " pixel " << p;
    }
    // The corners of a strongly distorted 8x8 image see outside it: undistortion changed the frame.
    EXPECT_EQ(frame.depth_raw.at(0, 0), 0);

    ThreadedSourceOptions raw;
    raw.undistort = false;
    auto untouched = threaded(script, std::make_shared<Progress>(), raw);
    EXPECT_TRUE(untouched->calib().depth_distortion.any());
    ASSERT_TRUE(untouched->next(frame));
    EXPECT_EQ(frame.depth_raw.at(0, 0), 1);
}

// One undistortion rule: the frames an engine gets do not depend on whether they were read ahead.
TEST(FramesForEngine, UndistortWhetherOrNotTheyAreReadAhead) {
    Watchdog watchdog(30s, "UndistortWhetherOrNotTheyAreReadAhead");
    Script script;
    script.frames = 3;
    script.depth_distortion = LensDistortion{1.0f, 0.f, 0.f, 0.f, 0.f};
    auto direct = framesForEngine(std::make_unique<ScriptedSource>(script, std::make_shared<Progress>()), false);
    auto ahead = framesForEngine(std::make_unique<ScriptedSource>(script, std::make_shared<Progress>()), true);
    EXPECT_FALSE(direct->calib().depth_distortion.any());
    EXPECT_FALSE(ahead->calib().depth_distortion.any());
    EXPECT_NE(dynamic_cast<ThreadedImageSource*>(ahead.get()), nullptr);
    EXPECT_EQ(dynamic_cast<ThreadedImageSource*>(direct.get()), nullptr);
    RGBDFrame a, b;
    for (int i = 0; i < 3; ++i) {
        ASSERT_TRUE(direct->next(a));
        ASSERT_TRUE(ahead->next(b));
        ASSERT_EQ(a.depth_raw.size(), b.depth_raw.size());
        EXPECT_EQ(std::memcmp(a.depth_raw.host(), b.depth_raw.host(), a.depth_raw.pixelCount() * sizeof(std::uint16_t)),
                  0)
            << "frame " << i;
    }
    EXPECT_EQ(a.depth_raw.at(0, 0), 0);  // undistorted: the corner sees outside the raw image
    // Without distortion the source itself is handed over, unwrapped.
    Script plain;
    plain.frames = 1;
    auto unwrapped = framesForEngine(std::make_unique<ScriptedSource>(plain, std::make_shared<Progress>()), false);
    EXPECT_NE(dynamic_cast<ScriptedSource*>(unwrapped.get()), nullptr);
}

}  // namespace
}  // namespace voxfuse
