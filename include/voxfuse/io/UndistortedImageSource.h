#pragma once
// Frames without lens distortion, whichever way they are read. Every front-end hands the engine its
// frames through framesForEngine(), so that a calibration with distortion coefficients gives the
// same map whether the frames are read on the caller's thread or ahead of it on a reader thread.

#include <memory>
#include <string>
#include <vector>

#include "voxfuse/io/FrameUndistorter.h"
#include "voxfuse/io/ImageSource.h"

namespace voxfuse {

// The source's frames remapped by a FrameUndistorter (depth, colour and label images), with the
// calibration they then have: the source's, without distortion.
class UndistortedImageSource : public ImageSource {
public:
    explicit UndistortedImageSource(std::unique_ptr<ImageSource> source);

    const RGBDCalib& calib() const override { return undistorter_.undistortedCalib(); }
    // The source's next frame, undistorted. An image whose size is not its camera's is an IoError
    // naming the frame (the next call moves on, as with any source).
    bool next(RGBDFrame& frame) override;
    int frameCount() const override { return source_->frameCount(); }
    std::string description() const override { return "undistorting " + source_->description(); }
    const std::vector<TimedPose>& groundTruth() const override { return source_->groundTruth(); }
    bool isLive() const override { return source_->isLive(); }

private:
    std::unique_ptr<ImageSource> source_;
    FrameUndistorter undistorter_;
    FrameImageBuffers scratch_;  // what frames are undistorted into (see FrameUndistorter::apply)
};

// `source` itself when its calibration has no lens distortion, else wrapped in an UndistortedImageSource.
std::unique_ptr<ImageSource> undistorted(std::unique_ptr<ImageSource> source);

// The one rule for handing frames to an engine: without lens distortion, and read ahead on a reader
// thread (ThreadedImageSource) when `read_ahead` is set or the source is a live camera.
std::unique_ptr<ImageSource> framesForEngine(std::unique_ptr<ImageSource> source, bool read_ahead);

}  // namespace voxfuse
