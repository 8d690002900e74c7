#pragma once
// Internal helpers shared by the image sources: read one frame's depth or colour file, whatever its
// format, and turn every failure into an IoError that names the file and the frame.

#include <cstdint>
#include <string>
#include <vector>

#include "voxfuse/core/Image.h"
#include "voxfuse/objects/Intrinsics.h"

namespace voxfuse {
namespace frame_reading {

bool fileExists(const std::string& path);
// For files a source reads when they are there (groundtruth.txt, calib.txt, pose files): false when
// nothing has the name, true for a file, IoError "is a folder, not a file" for anything else.
bool optionalFilePresent(const std::string& path);

struct ListedImage {
    double time_s;
    std::string path;  // resolved against the list file's folder, unless absolute
    bool on_disk;
};

// A list of images in the layout of TUM's rgb.txt: '#' comments and blank lines, else one
// "timestamp filename" line per image, in file order. Images not on disk are kept with on_disk false
// (their place may matter) and counted in `missing`; a listed name that is a folder counts as on
// disk, so that reading it says what it is. Throws IoError when the list cannot be read,
// ParseError naming the line for a malformed one.
std::vector<ListedImage> readTimestampedImageList(const std::string& list_path, int& missing);

// .pgm -> 16-bit big-endian PGM, anything else -> 16-bit single-channel PNG (or TIFF: any format
// io/ImageIO.h reads). The image must have the calibrated depth camera's size.
// Decoded into `depth`, whose memory is reused when it has the size (io/ImageIO.h). Returns the samples
// above the maximum the file declares (a PGM's maxval), which are read as no measurement.
std::size_t readDepth(const std::string& path, int frame, const Intrinsics& depth_camera, Image<std::uint16_t>& depth);

// Any colour image io/ImageIO.h reads, converted to RGBA. The image must have
// the calibrated RGB camera's size. Returns the samples above a PPM's maxval (read as full intensity).
std::size_t readColor(const std::string& path, int frame, const Intrinsics& rgb_camera, Image<Vec4u8>& rgb);

// Samples outside the range their files declare, per image of a frame.
struct SamplesOutOfRange {
    std::size_t depth = 0;  // read as no measurement
    std::size_t color = 0;  // read as full intensity
};

// Both images of one frame (the colour only when `color_path` is not empty), decoded at the same
// time, the colour on a second thread: they do not depend on each other, and decoding them one after
// the other is a noticeable part of a frame's time. One after the other when no thread can be had. Both are waited for;
// when both fail, the depth's error is the one thrown. Returns readDepth's and readColor's counts.
SamplesOutOfRange readDepthAndColor(const std::string& depth_path, const std::string& color_path, int frame,
                                    const Intrinsics& depth_camera, const Intrinsics& rgb_camera,
                                    Image<std::uint16_t>& depth, Image<Vec4u8>& rgb);

}  // namespace frame_reading
}  // namespace voxfuse
