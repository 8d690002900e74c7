#include "FrameReading.h"

#include <cctype>
#include <cmath>
#include <filesystem>
#include <future>
#include <system_error>

#include "TextParsing.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/ImageIO.h"

namespace voxfuse {
namespace frame_reading {

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
    if (s.size() < suffix.size()) return false;
    for (std::size_t i = 0; i < suffix.size(); ++i)
        if (std::tolower(static_cast<unsigned char>(s[s.size() - suffix.size() + i])) != suffix[i]) return false;
    return true;
}

std::string sizeText(Vec2i size) { return std::to_string(size.x) + "x" + std::to_string(size.y); }

// A wrong-sized image would be silently misread by every later stage, so it is a frame error here.
void requireSize(const std::string& path, int frame, Vec2i actual, const Intrinsics& camera, const char* what) {
    if (actual != camera.size())
        throw IoError(path,
                      std::string(what) + " image is " + sizeText(actual) + " but the calibration's " + what +
                          " camera is " + sizeText(camera.size()),
                      frame);
}

// Runs `read` and re-throws its IoError with the frame number attached.
template <typename Read>
auto withFrame(int frame, Read read) -> decltype(read()) {
    try {
        return read();
    } catch (const IoError& e) {
        throw IoError(e.file(), e.reason(), frame);
    }
}

}  // namespace

bool fileExists(const std::string& path) {
    std::error_code ec;
    return std::filesystem::is_regular_file(path, ec);
}

bool optionalFilePresent(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) return false;
    if (!std::filesystem::is_regular_file(path, ec)) throw IoError(path, "is a folder, not a file");
    return true;
}

std::vector<ListedImage> readTimestampedImageList(const std::string& list_path, int& missing) {
    text::LineReader in(list_path, "image list");
    const std::filesystem::path folder = std::filesystem::path(list_path).parent_path();
    std::vector<ListedImage> images;
    std::string line;
    while (in.next(line)) {
        const int line_number = in.lineNumber();
        if (text::isBlankOrComment(line)) continue;
        const auto tokens = text::splitWhitespace(line);
        if (tokens.size() != 2)
            throw ParseError(list_path, line_number,
                             "expected 'timestamp filename', got " + std::to_string(tokens.size()) + " fields");
        double time = 0.0;
        if (!text::parseDouble(tokens[0], time) || !std::isfinite(time))
            throw ParseError(list_path, line_number, "not a timestamp: " + text::excerpt(tokens[0]));
        const std::filesystem::path file{std::string(tokens[1])};
        const std::string resolved = (file.is_absolute() ? file : folder / file).string();
        std::error_code ec;
        const bool on_disk = std::filesystem::exists(resolved, ec);
        images.push_back({time, resolved, on_disk});
        missing += !on_disk;
    }
    return images;
}

std::size_t readDepth(const std::string& path, int frame, const Intrinsics& depth_camera, Image<std::uint16_t>& depth) {
    std::size_t out_of_range = 0;
    withFrame(frame, [&] {
        if (endsWith(path, ".pgm"))
            out_of_range = readPGM16(path, depth);
        else
            readDepthPNG(path, depth);
    });
    requireSize(path, frame, depth.size(), depth_camera, "depth");
    return out_of_range;
}

std::size_t readColor(const std::string& path, int frame, const Intrinsics& rgb_camera, Image<Vec4u8>& rgb) {
    std::size_t out_of_range = 0;
    withFrame(frame, [&] { out_of_range = readColorImage(path, rgb); });
    requireSize(path, frame, rgb.size(), rgb_camera, "rgb");
    return out_of_range;
}

SamplesOutOfRange readDepthAndColor(const std::string& depth_path, const std::string& color_path, int frame,
                                    const Intrinsics& depth_camera, const Intrinsics& rgb_camera,
                                    Image<std::uint16_t>& depth, Image<Vec4u8>& rgb) {
    SamplesOutOfRange out_of_range;
    if (color_path.empty()) {
        out_of_range.depth = readDepth(depth_path, frame, depth_camera, depth);
        return out_of_range;
    }
    std::future<std::size_t> color;
    try {
        color = std::async(std::launch::async, [&] { return readColor(color_path, frame, rgb_camera, rgb); });
    } catch (const std::system_error&) {
        // No thread to be had (a process limit): one after the other.
        out_of_range.depth = readDepth(depth_path, frame, depth_camera, depth);
        out_of_range.color = readColor(color_path, frame, rgb_camera, rgb);
        return out_of_range;
    }
    try {
        out_of_range.depth = readDepth(depth_path, frame, depth_camera, depth);
    } catch (...) {
        color.wait();  // it writes into `rgb`, which the caller owns
        throw;
    }
    out_of_range.color = color.get();
    return out_of_range;
}

}  // namespace frame_reading
}  // namespace voxfuse
