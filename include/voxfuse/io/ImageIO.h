#pragma once
// Image files: PPM/PGM by hand (InfiniTAM's 16-bit big-endian PGM depth is not what image libraries
// expect), PNG, JPEG and TIFF through libpng, TurboJPEG and libtiff, BMP by hand. Every failure
// throws IoError naming the file and the reason (missing, truncated, wrong magic, wrong bit depth,
// size mismatch...).

#include <cstdint>
#include <string>

#include "voxfuse/core/Image.h"
#include "voxfuse/objects/ClassLabel.h"

namespace voxfuse {

Image<Vec4u8> readPPM(const std::string& path);           // 8-bit P6 (maxval <= 255)
Image<std::uint16_t> readPGM16(const std::string& path);  // P5 with maxval > 255: 16-bit big-endian
void writePPM(const std::string& path, const Image<Vec4u8>& rgb);
void writePGM16(const std::string& path, const Image<std::uint16_t>& depth);

Image<Vec4u8> readColorImage(const std::string& path);       // PNG/JPEG/PPM..., any channel count -> RGBA
Image<std::uint16_t> readDepthPNG(const std::string& path);  // must be single-channel 16-bit
// RGB, or RGBA where some pixel is not opaque. The name must end in .png (IoError otherwise).
void writePNG(const std::string& path, const Image<Vec4u8>& rgba);

// The same readers decoding into `image`, whose memory is kept when it has the file's size already:
// a sequence of frames read into the same images allocates nothing per frame. After an error the
// image's contents are unspecified.
// These two return the colour samples above the maxval a PPM declares (read as full intensity; 0 for
// other formats).
std::size_t readPPM(const std::string& path, Image<Vec4u8>& image);
// A depth PGM's samples above the maxval its header declares are invalid: they are read as 0 (no
// measurement), and this readPGM16 returns how many there were.
std::size_t readPGM16(const std::string& path, Image<std::uint16_t>& image);
std::size_t readColorImage(const std::string& path, Image<Vec4u8>& image);
void readDepthPNG(const std::string& path, Image<std::uint16_t>& image);

void writeDepthPNG(const std::string& path, const Image<std::uint16_t>& depth);  // 16-bit grey, name *.png

// A semantic label image: one class id per pixel, in a single-channel lossless file: PNG (1 to 16-bit
// grey), binary PGM (any maxval), TIFF... Ids are taken as stored, never rescaled to the file's range.
// Pixels equal to `ignore_id` (-1: none) and 65535 become kNoLabel; 255 in an 8-bit image stays class
// 255 unless it is the ignore id. Colour-coded or palette images, float images and unreadable files
// throw IoError naming the file and the reason; an ignore_id outside -1..65535 throws ConfigError.
Image<ClassId> readLabelImage(const std::string& path, int ignore_id);

}  // namespace voxfuse
