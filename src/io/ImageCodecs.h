#pragma once
// Internal: the image decoders and the PNG encoder behind ImageIO.h, each over a well-kept library
// (libpng, libtiff, TurboJPEG) or by hand (Netpbm, BMP: a header and raw rows). They decode into
// DecodedImage, the samples as the file stores them, and ImageIO converts from there. OpenCV's
// codecs did this before; they load GDAL, Poppler and GDCM with them, 38 MB of every process's
// memory for formats no RGB-D camera writes.
//
// Every decoder is given the whole file in memory, after image_header has checked that the format is
// one VoxFuse reads and that the size its header claims is plausible. Each throws IoError naming
// `path` when the file is damaged; none writes to stderr.

#include <cstdint>
#include <string>
#include <vector>

#include "voxfuse/core/Image.h"

namespace voxfuse {
namespace codecs {

// Samples in the file's channel order (grey; grey, alpha; R, G, B; R, G, B, A), rows packed, 16-bit
// samples in host byte order. `maxval` is the sample that means full intensity: 255 or 65535, the top
// of a 1-, 2- or 4-bit grey PNG's range (its samples are kept as stored, not stretched to 0..255:
// label images hold class ids in them), or a Netpbm file's maxval.
struct DecodedImage {
    Vec2i size{0, 0};
    int channels = 0;          // 1 to 4
    int bytes_per_sample = 1;  // 1 or 2
    unsigned maxval = 255;
    std::vector<std::uint8_t> samples;  // its capacity is kept from image to image

    void reset(Vec2i image_size, int channel_count, int sample_bytes, unsigned full_intensity);
    std::size_t rowBytes() const { return std::size_t(size.x) * std::size_t(channels) * std::size_t(bytes_per_sample); }
    std::uint8_t* row(int y) { return samples.data() + std::size_t(y) * rowBytes(); }
    const std::uint8_t* row(int y) const { return samples.data() + std::size_t(y) * rowBytes(); }
    // Sample `c` of pixel `x` in row `y`, 8- or 16-bit alike.
    unsigned sample(int x, int y, int c) const;
    std::string describe() const;  // e.g. "16-bit 1-channel"
};

using Bytes = std::vector<unsigned char>;

// Any image file VoxFuse reads, decoded as stored, after the checks every reader makes (a file, a
// format VoxFuse reads, a plausible size). Defined in ImageIO.cpp, with those checks.
void readImageFile(const std::string& path, DecodedImage& image);

void decodePng(const std::string& path, const Bytes& file, DecodedImage& image);
void decodeTiff(const std::string& path, const Bytes& file, DecodedImage& image);
void decodeBmp(const std::string& path, const Bytes& file, DecodedImage& image);
// Colour JPEGs (CMYK ones converted as Adobe writes them) as RGB, grey ones as grey. Damage that
// libjpeg only warns about (a truncated or garbled file) is an error here.
void decodeJpeg(const std::string& path, const Bytes& file, DecodedImage& image);
// The same straight into RGBA: the colour frames of JPEG sequences, without a copy.
void decodeJpegToRgba(const std::string& path, const Bytes& file, Image<Vec4u8>& rgba);

// A PNG of `size` pixels of `channels` (1 to 4) 8- or 16-bit samples in host order, packed rows.
Bytes encodePng(const std::string& path, Vec2i size, int channels, int bytes_per_sample, const void* samples);

}  // namespace codecs
}  // namespace voxfuse
