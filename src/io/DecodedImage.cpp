// DecodedImage (ImageCodecs.h): the samples of an image file as it stores them.

#include <cstring>

#include "ImageCodecs.h"

namespace voxfuse {
namespace codecs {

void DecodedImage::reset(Vec2i image_size, int channel_count, int sample_bytes, unsigned full_intensity) {
    size = image_size;
    channels = channel_count;
    bytes_per_sample = sample_bytes;
    maxval = full_intensity;
    samples.resize(rowBytes() * std::size_t(size.y));
}

unsigned DecodedImage::sample(int x, int y, int c) const {
    const std::uint8_t* p =
        row(y) + (std::size_t(x) * std::size_t(channels) + std::size_t(c)) * std::size_t(bytes_per_sample);
    if (bytes_per_sample == 1) return *p;
    std::uint16_t v;
    std::memcpy(&v, p, 2);
    return v;
}

std::string DecodedImage::describe() const {
    return std::to_string(8 * bytes_per_sample) + "-bit " + std::to_string(channels) + "-channel";
}

}  // namespace codecs
}  // namespace voxfuse
