#pragma once
// Internal: what libvoxfuse asks of its video module. Decoding video needs OpenCV's videoio, which
// loads FFmpeg, GStreamer and OpenCV's image codecs (63 MB of a process's memory) with it; only
// Stray Scanner captures (rgb.mp4) need it. So videoio lives in a module of its own,
// libvoxfuse_video.so (VideoDecoderOpenCV.cpp), which VideoFrameReader loads the first time a video
// is opened, from the folder libvoxfuse itself was loaded from.
//
// Both sides are built together from this header and share libvoxfuse_core (Image, IoError): the
// module's functions throw IoError as any of the library's do.

#include <string>

#include "voxfuse/core/Image.h"

namespace voxfuse {

class VideoDecoder {
public:
    virtual ~VideoDecoder() = default;
    virtual Vec2i size() const = 0;
    virtual int frameCount() const = 0;          // -1 when the container does not say
    virtual double framesPerSecond() const = 0;  // 0 when unknown
    virtual bool skip() = 0;                     // drops the next frame; false at the end
    // Decodes the next frame into RGBA at `output_size` (area averaging). False at the end; IoError
    // naming `frame` when decoding fails.
    virtual bool read(Image<Vec4u8>& rgba, Vec2i output_size, int frame) = 0;
};

// The module's one entry point: opens `path`, or throws IoError saying why not.
using OpenVideoDecoderFunction = VideoDecoder* (*)(const std::string& path);
constexpr const char* kOpenVideoDecoderSymbol = "voxfuse_open_video_decoder";

}  // namespace voxfuse
