#include "voxfuse/io/UndistortedImageSource.h"

#include "voxfuse/core/Error.h"
#include "voxfuse/io/ThreadedImageSource.h"

namespace voxfuse {

namespace {

std::unique_ptr<ImageSource> requireSource(std::unique_ptr<ImageSource> source) {
    if (!source) throw ConfigError("UndistortedImageSource: no source given");
    return source;
}

}  // namespace

UndistortedImageSource::UndistortedImageSource(std::unique_ptr<ImageSource> source)
    : source_(requireSource(std::move(source))), undistorter_(source_->calib()) {}

bool UndistortedImageSource::next(RGBDFrame& frame) {
    if (!source_->next(frame)) return false;
    undistorter_.apply(frame, scratch_);
    return true;
}

std::unique_ptr<ImageSource> undistorted(std::unique_ptr<ImageSource> source) {
    if (!source) throw ConfigError("undistorted: no source given");
    const RGBDCalib& calib = source->calib();
    if (!calib.rgb_distortion.any() && !calib.depth_distortion.any()) return source;
    return std::make_unique<UndistortedImageSource>(std::move(source));
}

std::unique_ptr<ImageSource> framesForEngine(std::unique_ptr<ImageSource> source, bool read_ahead) {
    if (!source) throw ConfigError("framesForEngine: no source given");
    // The reader thread undistorts too (ThreadedSourceOptions::undistort), off the engine's thread.
    if (read_ahead || source->isLive()) return std::make_unique<ThreadedImageSource>(std::move(source));
    return undistorted(std::move(source));
}

}  // namespace voxfuse
