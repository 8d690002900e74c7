#pragma once
// Internal: sequential decoding of a colour video (e.g. an iPhone capture's rgb.mp4: H.264 or HEVC)
// through the video module (VideoDecoder.h), loaded the first time a video is opened.

#include <memory>
#include <string>

#include "voxfuse/core/Image.h"

namespace voxfuse {

class VideoFrameReader {
public:
    // Opens the video and reads its size. Throws IoError naming the file when it is missing, the
    // video module cannot be loaded, or no video backend of its OpenCV can decode it.
    explicit VideoFrameReader(const std::string& path);
    ~VideoFrameReader();
    VideoFrameReader(const VideoFrameReader&) = delete;
    VideoFrameReader& operator=(const VideoFrameReader&) = delete;

    Vec2i size() const { return size_; }
    // As the container says; -1 when it does not say. Containers can be off by a frame or two.
    int frameCount() const { return frame_count_; }
    double framesPerSecond() const { return fps_; }  // 0 when unknown

    // Decodes frame `index` (0-based) into RGBA, resized (area averaging) to `output_size`. Frames
    // are decoded in order: frames before `index` that were not asked for are decoded and dropped,
    // and asking for an earlier frame than the last throws IoError. Returns false when the video
    // ends before `index`; throws IoError (naming file and frame) if decoding fails.
    bool read(int index, Image<Vec4u8>& rgba, Vec2i output_size);

private:
    struct Capture;
    std::string path_;
    std::unique_ptr<Capture> capture_;
    Vec2i size_{0, 0};
    int frame_count_ = -1;
    double fps_ = 0.0;
    int next_index_ = 0;  // index of the frame the decoder delivers next
    bool ended_ = false;
};

}  // namespace voxfuse
