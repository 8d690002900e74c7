// JPEG through TurboJPEG. A damaged or truncated JPEG is an error here: libjpeg would decode it into a
// partly grey image and only warn (TJFLAG_STOPONWARNING makes the warning the error it is).

#include <memory>

#include <turbojpeg.h>

#include "ImageCodecs.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace codecs {

namespace {

using Decoder = std::unique_ptr<void, int (*)(tjhandle)>;

struct JpegHeader {
    Vec2i size{0, 0};
    int colorspace = 0;
};

JpegHeader readHeader(const std::string& path, const Bytes& file, const Decoder& tj) {
    if (!tj) throw IoError(path, "cannot start the JPEG decoder");
    int width = 0, height = 0, subsampling = 0, colorspace = 0;
    if (tjDecompressHeader3(tj.get(), file.data(), static_cast<unsigned long>(file.size()), &width, &height,
                            &subsampling, &colorspace) != 0)
        throw IoError(path, std::string("corrupt JPEG: ") + tjGetErrorStr2(tj.get()));
    if (width <= 0 || height <= 0) throw IoError(path, "corrupt JPEG: the header gives no image size");
    return JpegHeader{Vec2i{width, height}, colorspace};
}

void decompress(const std::string& path, const Bytes& file, const Decoder& tj, Vec2i size, int pixel_format,
                void* into) {
    if (tjDecompress2(tj.get(), file.data(), static_cast<unsigned long>(file.size()), static_cast<unsigned char*>(into),
                      size.x, 0, size.y, pixel_format, TJFLAG_STOPONWARNING) != 0)
        throw IoError(path,
                      std::string("corrupt JPEG: ") + tjGetErrorStr2(tj.get()) + " (the file is damaged or truncated)");
}

bool isCmyk(int colorspace) { return colorspace == TJCS_CMYK || colorspace == TJCS_YCCK; }

// Adobe's CMYK JPEGs store inverted inks, as libjpeg hands them over: R = C K / 255 (so for G, B).
std::uint8_t fromInvertedInk(unsigned ink, unsigned black) { return std::uint8_t((ink * black + 127) / 255); }

}  // namespace

void decodeJpeg(const std::string& path, const Bytes& file, DecodedImage& image) {
    const Decoder tj(tjInitDecompress(), tjDestroy);
    const JpegHeader h = readHeader(path, file, tj);
    if (isCmyk(h.colorspace)) {
        std::vector<std::uint8_t> cmyk(std::size_t(h.size.x) * std::size_t(h.size.y) * 4);
        decompress(path, file, tj, h.size, TJPF_CMYK, cmyk.data());
        image.reset(h.size, 3, 1, 255);
        std::uint8_t* out = image.samples.data();
        for (std::size_t i = 0; i < cmyk.size(); i += 4)
            for (int c = 0; c < 3; ++c) *out++ = fromInvertedInk(cmyk[i + std::size_t(c)], cmyk[i + 3]);
        return;
    }
    const bool grey = h.colorspace == TJCS_GRAY;
    image.reset(h.size, grey ? 1 : 3, 1, 255);
    decompress(path, file, tj, h.size, grey ? TJPF_GRAY : TJPF_RGB, image.samples.data());
}

void decodeJpegToRgba(const std::string& path, const Bytes& file, Image<Vec4u8>& rgba) {
    const Decoder tj(tjInitDecompress(), tjDestroy);
    const JpegHeader h = readHeader(path, file, tj);
    if (isCmyk(h.colorspace)) {  // rare: through the converting decoder
        DecodedImage rgb;
        decodeJpeg(path, file, rgb);
        rgba.resize(rgb.size);
        const std::uint8_t* in = rgb.samples.data();
        for (std::size_t i = 0; i < rgba.pixelCount(); ++i, in += 3) rgba.host()[i] = Vec4u8{in[0], in[1], in[2], 255};
        return;
    }
    rgba.resize(h.size);
    decompress(path, file, tj, h.size, TJPF_RGBA, rgba.host());
}

}  // namespace codecs
}  // namespace voxfuse
