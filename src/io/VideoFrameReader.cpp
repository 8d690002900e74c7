#include "VideoFrameReader.h"

#include <cmath>
#include <filesystem>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <opencv2/videoio/registry.hpp>

#include "voxfuse/core/Error.h"

namespace voxfuse {

struct VideoFrameReader::Capture {
    cv::VideoCapture video;
};

VideoFrameReader::VideoFrameReader(const std::string& path) : path_(path), capture_(std::make_unique<Capture>()) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw IoError(path, "no such file");
    // FFmpeg decodes H.264 and HEVC; only an OpenCV built without it gets to try its other backends
    // (probing those, GStreamer especially, is slow and noisy for a file FFmpeg has rejected).
    const bool has_ffmpeg = cv::videoio_registry::hasBackend(cv::CAP_FFMPEG);
    if (!capture_->video.open(path, has_ffmpeg ? cv::CAP_FFMPEG : cv::CAP_ANY))
        throw IoError(path, has_ffmpeg ? "FFmpeg (through OpenCV) cannot open this video: not a video file, or a "
                                         "damaged one"
                                       : "OpenCV cannot open this video: this OpenCV build has no FFmpeg, and no "
                                         "other video backend reads the file (see cv::getBuildInformation(), "
                                         "'Video I/O')");
    cv::VideoCapture& video = capture_->video;
    size_ = Vec2i{int(video.get(cv::CAP_PROP_FRAME_WIDTH)), int(video.get(cv::CAP_PROP_FRAME_HEIGHT))};
    const double count = video.get(cv::CAP_PROP_FRAME_COUNT);
    frame_count_ = count > 0.0 && std::isfinite(count) ? int(std::lround(count)) : -1;
    const double fps = video.get(cv::CAP_PROP_FPS);
    fps_ = fps > 0.0 && std::isfinite(fps) ? fps : 0.0;
    if (size_.x <= 0 || size_.y <= 0) throw IoError(path, "the video does not say its frame size (not a video?)");
}

VideoFrameReader::~VideoFrameReader() = default;

bool VideoFrameReader::read(int index, Image<Vec4u8>& rgba, Vec2i output_size) {
    if (index < next_index_)
        throw IoError(path_,
                      "video frames are decoded in order: frame " + std::to_string(index) +
                          " was asked for after frame " + std::to_string(next_index_ - 1),
                      index);
    cv::VideoCapture& video = capture_->video;
    for (; !ended_ && next_index_ < index; ++next_index_)
        if (!video.grab()) ended_ = true;
    if (ended_) return false;
    cv::Mat bgr;
    if (!video.read(bgr) || bgr.empty()) {
        ended_ = true;
        return false;
    }
    ++next_index_;
    if (bgr.type() != CV_8UC3)
        throw IoError(path_,
                      "the video decodes to an unexpected pixel type (OpenCV type " + std::to_string(bgr.type()) +
                          "), expected 8-bit colour",
                      index);
    if (bgr.cols != size_.x || bgr.rows != size_.y) throw IoError(path_, "frame size changed within the video", index);
    if (output_size != size_) {
        cv::Mat resized;
        cv::resize(bgr, resized, cv::Size(output_size.x, output_size.y), 0.0, 0.0, cv::INTER_AREA);
        bgr = resized;
    }
    rgba.resize(output_size);
    cv::Mat out(output_size.y, output_size.x, CV_8UC4, static_cast<void*>(rgba.host()));
    cv::cvtColor(bgr, out, cv::COLOR_BGR2RGBA);
    return true;
}

}  // namespace voxfuse
