#pragma once
// Reads (decodes, undistorts) frames on a thread of its own, ahead of the engine, through a bounded
// queue: the engine's frame time no longer includes PNG/JPEG/video decoding and remapping.

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "voxfuse/io/ImageSource.h"

namespace voxfuse {

struct ThreadedSourceOptions {
    // Frames decoded ahead of the engine. A few are enough to hide decoding jitter; each costs one
    // frame of memory and, for live cameras, one frame of latency.
    int queue_capacity = 4;

    enum class WhenFull {
        Automatic,  // DropOldest for live sources (ImageSource::isLive), Wait for recordings
        Wait,       // the reader waits for room: no frame is lost
        DropOldest  // the oldest queued frame is discarded (counted): the engine always gets the newest
    };
    WhenFull when_full = WhenFull::Automatic;

    // Remove lens distortion with the calibration's coefficients (FrameUndistorter) on the reader
    // thread. Without coefficients in the calibration this does nothing.
    bool undistort = true;
};

class ThreadedImageSource : public ImageSource {
public:
    // Takes the source over and starts reading at once. Throws ConfigError for a capacity < 1.
    explicit ThreadedImageSource(std::unique_ptr<ImageSource> source, const ThreadedSourceOptions& options = {});
    // Stops the reader and joins it. Never waits for the consumer; it waits at most for the one
    // source->next() call in progress (a camera's frame timeout in the worst case).
    ~ThreadedImageSource() override;
    ThreadedImageSource(const ThreadedImageSource&) = delete;
    ThreadedImageSource& operator=(const ThreadedImageSource&) = delete;

    // The source's calibration; without lens distortion when the frames are undistorted.
    const RGBDCalib& calib() const override;
    // The source's frames in the source's order. An IoError that the source threw for a frame is
    // rethrown here, at that frame's place, and the next call moves on, as with the source itself.
    // Any other exception is rethrown at its place too, but ends the sequence: the reader stops and
    // later calls return false. Call from one thread only.
    bool next(RGBDFrame& frame) override;
    // Whether next() would return at once (a frame, a frame's error or the end), waiting for that at
    // most `timeout`: an interactive caller keeps serving its window while a camera is silent.
    bool waitForFrame(std::chrono::milliseconds timeout);
    int frameCount() const override;
    std::string description() const override;
    const std::vector<TimedPose>& groundTruth() const override;
    bool isLive() const override;

    // Frames (or frame errors) discarded because the queue was full: always 0 with WhenFull::Wait.
    long droppedFrames() const;

private:
    struct State;
    std::unique_ptr<State> state_;
};

}  // namespace voxfuse
