#include "VideoFrameReader.h"

#include <dlfcn.h>

#include <filesystem>
#include <mutex>

#include "VideoDecoder.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {

namespace {

// The video module's entry point, loaded once per process: from the folder this library was loaded
// from (the build tree, an install, a wheel's voxfuse/lib alike), else wherever the loader finds it.
// The module is never unloaded: decoders made by it may outlive any one reader.
OpenVideoDecoderFunction videoModule(const std::string& video_path) {
    static std::once_flag once;
    static OpenVideoDecoderFunction entry = nullptr;
    static std::string failure;
    std::call_once(once, [] {
        std::string tried;
        Dl_info self{};
        void* handle = nullptr;
        if (dladdr(reinterpret_cast<void*>(&videoModule), &self) && self.dli_fname) {
            const std::string beside =
                (std::filesystem::path(self.dli_fname).parent_path() / VOXFUSE_VIDEO_MODULE).string();
            handle = dlopen(beside.c_str(), RTLD_NOW | RTLD_LOCAL);
            if (!handle) tried = dlerror();
        }
        if (!handle) handle = dlopen(VOXFUSE_VIDEO_MODULE, RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            failure = std::string(dlerror()) + (tried.empty() ? "" : "; " + tried);
            return;
        }
        entry = reinterpret_cast<OpenVideoDecoderFunction>(dlsym(handle, kOpenVideoDecoderSymbol));
        if (!entry) failure = std::string(VOXFUSE_VIDEO_MODULE) + " has no " + kOpenVideoDecoderSymbol;
    });
    if (!entry)
        throw IoError(video_path, std::string("cannot decode video: VoxFuse's video module (") + VOXFUSE_VIDEO_MODULE +
                                      ", installed beside libvoxfuse) cannot be loaded: " + failure);
    return entry;
}

}  // namespace

struct VideoFrameReader::Capture {
    std::unique_ptr<VideoDecoder> decoder;
};

VideoFrameReader::VideoFrameReader(const std::string& path) : path_(path), capture_(std::make_unique<Capture>()) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw IoError(path, "no such file");
    capture_->decoder.reset(videoModule(path)(path));
    const VideoDecoder& video = *capture_->decoder;
    size_ = video.size();
    frame_count_ = video.frameCount();
    fps_ = video.framesPerSecond();
}

VideoFrameReader::~VideoFrameReader() = default;

bool VideoFrameReader::read(int index, Image<Vec4u8>& rgba, Vec2i output_size) {
    if (index < next_index_)
        throw IoError(path_,
                      "video frames are decoded in order: frame " + std::to_string(index) +
                          " was asked for after frame " + std::to_string(next_index_ - 1),
                      index);
    VideoDecoder& video = *capture_->decoder;
    for (; !ended_ && next_index_ < index; ++next_index_)
        if (!video.skip()) ended_ = true;
    if (ended_) return false;
    if (!video.read(rgba, output_size, index)) {
        ended_ = true;
        return false;
    }
    ++next_index_;
    return true;
}

}  // namespace voxfuse
