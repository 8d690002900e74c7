#pragma once
// Image files: PPM/PGM by hand (InfiniTAM's 16-bit big-endian PGM depth is not what image libraries
// expect), PNG/JPEG through OpenCV. Every failure throws IoError naming the file and the reason
// (missing, truncated, wrong magic, wrong bit depth, size mismatch...).

#include <cstdint>
#include <string>

#include "voxfuse/core/Image.h"

namespace voxfuse {

Image<Vec4u8> readPPM(const std::string& path);            // 8-bit P6 (maxval <= 255)
Image<std::uint16_t> readPGM16(const std::string& path);   // P5 with maxval > 255: 16-bit big-endian
void writePPM(const std::string& path, const Image<Vec4u8>& rgb);
void writePGM16(const std::string& path, const Image<std::uint16_t>& depth);

Image<Vec4u8> readColorImage(const std::string& path);         // PNG/JPEG/PPM..., any channel count -> RGBA
Image<std::uint16_t> readDepthPNG(const std::string& path);    // must be single-channel 16-bit
void writePNG(const std::string& path, const Image<Vec4u8>& rgba);
void writeDepthPNG(const std::string& path, const Image<std::uint16_t>& depth);

}  // namespace voxfuse
