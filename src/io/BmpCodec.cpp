// BMP by hand: a header and uncompressed rows, which no library here reads without also bringing a
// toolkit. Read: 1, 4 and 8-bit palettes (grey when every entry is grey), 16 and 32-bit with channel
// masks, 24-bit. Refused with the reason: RLE or embedded JPEG/PNG compression, the OS/2 header.

#include <cstring>

#include "ImageCodecs.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace codecs {

namespace {

constexpr std::uint32_t kBiRgb = 0, kBiBitfields = 3, kBiAlphaBitfields = 6;

std::uint32_t le32(const unsigned char* p) {
    return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 | std::uint32_t(p[3]) << 24;
}
std::uint16_t le16(const unsigned char* p) { return std::uint16_t(p[0] | p[1] << 8); }

// One channel's bits in a 16 or 32-bit pixel, scaled to 0..255.
struct ChannelMask {
    std::uint32_t mask = 0;
    int shift = 0;
    std::uint32_t top = 0;  // the channel's largest value

    explicit ChannelMask(std::uint32_t m = 0) : mask(m) {
        if (!mask) return;
        while (!((mask >> shift) & 1u)) ++shift;
        top = mask >> shift;
    }
    std::uint8_t operator()(std::uint32_t pixel) const {
        return top ? std::uint8_t((((pixel & mask) >> shift) * 255u + top / 2) / top) : 255;
    }
};

}  // namespace

void decodeBmp(const std::string& path, const Bytes& file, DecodedImage& image) {
    const auto fail = [&](const std::string& reason) { throw IoError(path, "cannot decode image: " + reason); };
    if (file.size() < 14 + 40) fail("corrupt BMP: the file is too short for its headers");
    const std::uint32_t pixel_offset = le32(&file[10]);
    const std::uint32_t info_size = le32(&file[14]);
    if (info_size < 40) fail("an OS/2 BMP (its header has " + std::to_string(info_size) + " bytes): not read");
    if (14 + std::size_t(info_size) > file.size()) fail("corrupt BMP: the file ends inside its header");
    const std::int32_t width = std::int32_t(le32(&file[18])), signed_height = std::int32_t(le32(&file[22]));
    const int bits = le16(&file[28]);
    const std::uint32_t compression = le32(&file[30]);
    std::uint32_t palette_count = le32(&file[46]);
    if (width <= 0 || signed_height == 0 || signed_height == INT32_MIN) fail("corrupt BMP: no image size");
    const bool top_down = signed_height < 0;
    const Vec2i size{width, top_down ? -signed_height : signed_height};
    if (compression != kBiRgb && compression != kBiBitfields && compression != kBiAlphaBitfields)
        fail("a compressed BMP (compression " + std::to_string(compression) + ": RLE, JPEG or PNG): not read");
    if (bits != 1 && bits != 4 && bits != 8 && bits != 16 && bits != 24 && bits != 32)
        fail("corrupt BMP: " + std::to_string(bits) + " bits per pixel");

    // Masks: after a 40-byte header (3 or 4 of them), or inside a longer one at the same place.
    ChannelMask red, green, blue, alpha;
    if (bits == 16 || bits == 32) {
        if (compression == kBiRgb) {
            red = ChannelMask(bits == 16 ? 0x7c00u : 0x00ff0000u);
            green = ChannelMask(bits == 16 ? 0x03e0u : 0x0000ff00u);
            blue = ChannelMask(bits == 16 ? 0x001fu : 0x000000ffu);
        } else {
            const std::size_t with_alpha = compression == kBiAlphaBitfields || info_size >= 56 ? 16 : 12;
            if (54 + with_alpha > file.size()) fail("corrupt BMP: the file ends inside its channel masks");
            red = ChannelMask(le32(&file[54]));
            green = ChannelMask(le32(&file[58]));
            blue = ChannelMask(le32(&file[62]));
            if (with_alpha == 16) alpha = ChannelMask(le32(&file[66]));
        }
    }
    std::vector<Vec4u8> palette;  // R, G, B, unused
    bool grey_palette = true;
    if (bits <= 8) {
        if (palette_count == 0 || palette_count > (1u << bits)) palette_count = 1u << bits;
        const std::size_t at = 14 + info_size + (compression == kBiBitfields && info_size == 40 ? 12 : 0);
        if (at + 4 * std::size_t(palette_count) > file.size()) fail("corrupt BMP: the file ends inside its palette");
        for (std::uint32_t i = 0; i < palette_count; ++i) {
            const unsigned char* e = &file[at + 4 * i];
            palette.push_back(Vec4u8{e[2], e[1], e[0], 255});
            grey_palette = grey_palette && e[0] == e[1] && e[1] == e[2];
        }
    }
    const std::size_t stride = (std::size_t(size.x) * std::size_t(bits) + 31) / 32 * 4;
    if (pixel_offset > file.size() || (file.size() - pixel_offset) / stride < std::size_t(size.y))
        fail("truncated BMP: " + std::to_string(size.x) + "x" + std::to_string(size.y) + " needs " +
             std::to_string(stride * std::size_t(size.y)) + " bytes of pixels after byte " +
             std::to_string(pixel_offset) + ", the file has " + std::to_string(file.size()));

    const int channels = bits <= 8 ? (grey_palette ? 1 : 3) : bits == 24 || !alpha.mask ? 3 : 4;
    image.reset(size, channels, 1, 255);
    for (int y = 0; y < size.y; ++y) {
        const unsigned char* src = &file[pixel_offset + stride * std::size_t(top_down ? y : size.y - 1 - y)];
        std::uint8_t* dst = image.row(y);
        for (int x = 0; x < size.x; ++x) {
            if (bits <= 8) {
                const int bit = x * bits;
                const unsigned index = (src[bit / 8] >> (8 - bits - bit % 8)) & ((1u << bits) - 1u);
                if (index >= palette.size())
                    fail("corrupt BMP: pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                         ") uses palette entry " + std::to_string(index) + " of " + std::to_string(palette.size()));
                const Vec4u8 c = palette[index];
                if (channels == 1) {
                    *dst++ = c.x;
                } else {
                    *dst++ = c.x;
                    *dst++ = c.y;
                    *dst++ = c.z;
                }
            } else if (bits == 24) {
                const unsigned char* p = src + 3 * x;
                *dst++ = p[2];
                *dst++ = p[1];
                *dst++ = p[0];
            } else {
                const std::uint32_t p = bits == 16 ? le16(src + 2 * x) : le32(src + 4 * x);
                *dst++ = red(p);
                *dst++ = green(p);
                *dst++ = blue(p);
                if (channels == 4) *dst++ = alpha(p);
            }
        }
    }
}

}  // namespace codecs
}  // namespace voxfuse
