// The video module (VideoDecoder.h): sequential decoding through OpenCV's videoio, built as
// libvoxfuse_video.so and loaded only when a video is opened.

#include <cmath>
#include <memory>
#include <type_traits>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <opencv2/videoio/registry.hpp>

#include "VideoDecoder.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace {

class OpenCVVideoDecoder final : public VideoDecoder {
public:
    explicit OpenCVVideoDecoder(const std::string& path) : path_(path) {
        // FFmpeg decodes H.264 and HEVC; only an OpenCV built without it gets to try its other backends
        // (probing those, GStreamer especially, is slow and noisy for a file FFmpeg has rejected).
        const bool has_ffmpeg = cv::videoio_registry::hasBackend(cv::CAP_FFMPEG);
        if (!video_.open(path, has_ffmpeg ? cv::CAP_FFMPEG : cv::CAP_ANY))
            throw IoError(path, has_ffmpeg ? "FFmpeg (through OpenCV) cannot open this video: not a video file, or a "
                                             "damaged one"
                                           : "OpenCV cannot open this video: this OpenCV build has no FFmpeg, and no "
                                             "other video backend reads the file (see cv::getBuildInformation(), "
                                             "'Video I/O')");
        size_ = Vec2i{int(video_.get(cv::CAP_PROP_FRAME_WIDTH)), int(video_.get(cv::CAP_PROP_FRAME_HEIGHT))};
        const double count = video_.get(cv::CAP_PROP_FRAME_COUNT);
        frame_count_ = count > 0.0 && std::isfinite(count) ? int(std::lround(count)) : -1;
        const double fps = video_.get(cv::CAP_PROP_FPS);
        fps_ = fps > 0.0 && std::isfinite(fps) ? fps : 0.0;
        if (size_.x <= 0 || size_.y <= 0) throw IoError(path, "the video does not say its frame size (not a video?)");
    }

    Vec2i size() const override { return size_; }
    int frameCount() const override { return frame_count_; }
    double framesPerSecond() const override { return fps_; }
    bool skip() override { return video_.grab(); }

    bool read(Image<Vec4u8>& rgba, Vec2i output_size, int frame) override {
        if (!video_.read(bgr_) || bgr_.empty()) return false;
        if (bgr_.type() != CV_8UC3)
            throw IoError(path_,
                          "the video decodes to an unexpected pixel type (OpenCV type " + std::to_string(bgr_.type()) +
                              "), expected 8-bit colour",
                          frame);
        if (bgr_.cols != size_.x || bgr_.rows != size_.y)
            throw IoError(path_, "frame size changed within the video", frame);
        const cv::Mat* source = &bgr_;
        if (output_size != size_) {
            cv::resize(bgr_, resized_, cv::Size(output_size.x, output_size.y), 0.0, 0.0, cv::INTER_AREA);
            source = &resized_;
        }
        rgba.resize(output_size);
        cv::Mat out(output_size.y, output_size.x, CV_8UC4, static_cast<void*>(rgba.host()));
        cv::cvtColor(*source, out, cv::COLOR_BGR2RGBA);
        return true;
    }

private:
    std::string path_;
    cv::VideoCapture video_;
    cv::Mat bgr_, resized_;  // kept: decoding allocates nothing per frame
    Vec2i size_{0, 0};
    int frame_count_ = -1;
    double fps_ = 0.0;
};

}  // namespace
}  // namespace voxfuse

extern "C" __attribute__((visibility("default"))) voxfuse::VideoDecoder* voxfuse_open_video_decoder(
    const std::string& path) {
    return new voxfuse::OpenCVVideoDecoder(path);
}

static_assert(std::is_same_v<decltype(&voxfuse_open_video_decoder), voxfuse::OpenVideoDecoderFunction>,
              "the entry point must have the type VideoFrameReader looks it up as");
