#pragma once
// Internal: what an image file says about itself before it is decoded: its format, from its first
// bytes, and its size, from its header. The image readers hand a decoder only formats VoxFuse reads,
// and refuse a header whose size would make the decoder allocate gigabytes for a file of a few bytes.

#include <cstdint>
#include <string>

namespace voxfuse {
namespace image_header {

enum class Format { Png, Jpeg, Netpbm, Tiff, Bmp, Unknown };

struct Header {
    Format format = Format::Unknown;
    std::int64_t width = -1, height = -1;  // -1: the header does not say (or could not be read)
    std::uint64_t minimum_bytes = 0;       // uncompressed formats: the file size the pixels need
};

// Reads the first bytes of `path` (and, for TIFF, its first directory). Never throws for content:
// what cannot be recognised is Format::Unknown.
Header read(const std::string& path);

const char* name(Format format);

}  // namespace image_header
}  // namespace voxfuse
