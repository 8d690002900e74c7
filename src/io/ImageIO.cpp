// Image files. PPM/PGM are read and written by hand because InfiniTAM's depth PGMs are 16-bit
// big-endian and we want exact, explained errors for them; the other formats go through the codecs
// of ImageCodecs.h, and are converted here to what the caller asked for.

#include "voxfuse/io/ImageIO.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <vector>

#include "ImageCodecs.h"
#include "ImageHeader.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/AtomicFile.h"

namespace voxfuse {

namespace {

// ---------------------------------------------------------------------------------------------
// Netpbm (P5/P6)

// Image files larger than this many pixels are refused before they are decoded: a few bytes of
// header can otherwise ask for gigabytes (no camera delivers more than 2^26 pixels per frame).
constexpr double kMaxImagePixels = double(1 << 26);

void requireImageFile(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw IoError(path, "is a folder, not an image file");
    if (!std::filesystem::exists(path, ec)) throw IoError(path, "no such file");
}

// Into `bytes`, whose capacity is kept: read frame after frame, it stops allocating. The caller has
// checked that `path` is a file (requireImageFile), so that a missing file says so first.
void readWholeFile(const std::string& path, std::vector<unsigned char>& bytes) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) throw IoError(path, "cannot open for reading");
    const std::streamoff size = in.tellg();
    if (size < 0) throw IoError(path, "read error");
    // 2^26 pixels of 16-bit RGBA are 512 MiB even uncompressed: a larger file is no frame's image.
    if (size > (std::streamoff(1) << 30))
        throw IoError(path, "the file has " + std::to_string(size >> 20) +
                                " MiB: too large for an image of a frame (at most 1 GiB)");
    bytes.resize(std::size_t(size));
    in.seekg(0);
    if (!in.read(reinterpret_cast<char*>(bytes.data()), size)) throw IoError(path, "read error");
}

// What decoding a frame needs besides its image, kept per thread so that reading a sequence makes no
// megabyte allocation per frame. Buffers made and freed every frame fragment glibc's heap (once one
// is freed, later ones come from the heap rather than mmap, and the small long-lived allocations
// between them keep it from shrinking), so the peak memory of a long run grows. Depth and colour
// keep a decoded image each: sharing one would resize it twice a frame.
struct DecodeScratch {
    std::vector<unsigned char> bytes;  // the file
    codecs::DecodedImage depth;        // a decoded depth image
    codecs::DecodedImage color;        // a decoded colour image
};
DecodeScratch& decodeScratch() {
    thread_local DecodeScratch scratch;
    return scratch;
}

struct NetpbmHeader {
    int width = 0, height = 0, maxval = 0;
    std::size_t data_offset = 0;  // first byte of the pixel data
};

// Parses "P5"/"P6", width, height and maxval, with '#' comments and any whitespace between them,
// and exactly one whitespace byte before the pixel data (as the Netpbm spec requires).
class NetpbmHeaderParser {
public:
    NetpbmHeaderParser(const std::string& path, const std::vector<unsigned char>& bytes) : path_(path), bytes_(bytes) {}

    NetpbmHeader parse(char expected_kind, const char* format_name) {
        checkMagic(expected_kind, format_name);
        pos_ = 2;
        NetpbmHeader h;
        h.width = readNumber("width");
        h.height = readNumber("height");
        h.maxval = readNumber("maxval");
        if (h.width <= 0 || h.height <= 0)
            fail("bad header: width and height must be positive, got " + std::to_string(h.width) + "x" +
                 std::to_string(h.height));
        if (pos_ >= bytes_.size()) fail("truncated: the file ends right after the header, no pixel data");
        if (!std::isspace(bytes_[pos_])) fail("bad header: expected one whitespace byte after maxval");
        h.data_offset = pos_ + 1;
        return h;
    }

private:
    [[noreturn]] void fail(const std::string& reason) const { throw IoError(path_, reason); }

    void checkMagic(char expected_kind, const char* format_name) const {
        const std::string expected = std::string("P") + expected_kind;
        if (bytes_.size() < 2)
            fail("wrong magic: the file is too short to hold '" + expected + "' (" + format_name + ")");
        std::string got;
        for (int i = 0; i < 2; ++i) {
            const unsigned char c = bytes_[std::size_t(i)];
            got += std::isprint(c) ? std::string(1, char(c)) : "\\x" + std::to_string(int(c));
        }
        if (got != expected) fail("wrong magic '" + got + "': expected '" + expected + "' (" + format_name + ")");
        if (bytes_.size() > 2 && !std::isspace(bytes_[2]) && bytes_[2] != '#')
            fail("bad header: expected whitespace after '" + expected + "'");
    }

    void skipWhitespaceAndComments() {
        while (pos_ < bytes_.size()) {
            if (std::isspace(bytes_[pos_])) {
                ++pos_;
            } else if (bytes_[pos_] == '#') {
                while (pos_ < bytes_.size() && bytes_[pos_] != '\n' && bytes_[pos_] != '\r') ++pos_;
            } else {
                break;
            }
        }
    }

    int readNumber(const char* what) {
        skipWhitespaceAndComments();
        if (pos_ >= bytes_.size()) fail(std::string("bad header: file ends before the ") + what);
        if (!std::isdigit(bytes_[pos_]))
            fail(std::string("bad header: expected the ") + what + " (a decimal number), got '" + char(bytes_[pos_]) +
                 "'");
        long long value = 0;
        while (pos_ < bytes_.size() && std::isdigit(bytes_[pos_])) {
            value = value * 10 + (bytes_[pos_] - '0');
            if (value > 1000000000LL) fail(std::string("bad header: ") + what + " is absurdly large");
            ++pos_;
        }
        if (pos_ < bytes_.size() && !std::isspace(bytes_[pos_]) && bytes_[pos_] != '#')
            fail(std::string("bad header: unexpected character '") + char(bytes_[pos_]) + "' after the " + what);
        return int(value);
    }

    const std::string& path_;
    const std::vector<unsigned char>& bytes_;
    std::size_t pos_ = 0;
};

void requirePixelBytes(const std::string& path, const std::vector<unsigned char>& bytes, const NetpbmHeader& h,
                       std::size_t bytes_per_pixel) {
    const std::size_t needed = std::size_t(h.width) * std::size_t(h.height) * bytes_per_pixel;
    const std::size_t available = bytes.size() - h.data_offset;
    if (available < needed)
        throw IoError(path, "truncated: " + std::to_string(h.width) + "x" + std::to_string(h.height) + " needs " +
                                std::to_string(needed) + " bytes of pixel data, the file has " +
                                std::to_string(available));
}

void writeWholeFile(const std::string& path, const std::string& header, const std::vector<unsigned char>& data) {
    AtomicFile file(path);
    file.stream().write(header.data(), std::streamsize(header.size()));
    file.stream().write(reinterpret_cast<const char*>(data.data()), std::streamsize(data.size()));
    file.commit();
}

std::string netpbmHeader(const char* magic, Vec2i size, int maxval) {
    return std::string(magic) + "\n" + std::to_string(size.x) + " " + std::to_string(size.y) + "\n" +
           std::to_string(maxval) + "\n";
}

// ---------------------------------------------------------------------------------------------
// The other formats

// Only the formats VoxFuse reads reach a decoder, and only with a size a frame can have: a decoder
// allocates what a header claims before it reads a pixel.
image_header::Header requirePlausibleImage(const std::string& path) {
    const image_header::Header h = image_header::read(path);
    if (h.format == image_header::Format::Unknown)
        throw IoError(path, "cannot decode image: not a format VoxFuse reads (PNG, JPEG, PPM/PGM, TIFF or BMP)");
    const char* format = image_header::name(h.format);
    if (h.width >= 0 && double(h.width) * double(h.height) > kMaxImagePixels)
        throw IoError(path, std::string("the ") + format + " says it is " + std::to_string(h.width) + "x" +
                                std::to_string(h.height) +
                                " pixels: too large for an image of a frame (corrupt header?)");
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (!ec && h.minimum_bytes > size)
        throw IoError(path, std::string("truncated: a ") + std::to_string(h.width) + "x" + std::to_string(h.height) +
                                " " + format + " needs " + std::to_string(h.minimum_bytes) + " bytes, the file has " +
                                std::to_string(size));
    return h;
}

// Binary PGM or PPM of any maxval, samples as stored (maxval says what full intensity is).
void decodeNetpbm(const std::string& path, const std::vector<unsigned char>& bytes, codecs::DecodedImage& image) {
    if (bytes.size() < 2 || (bytes[1] != '5' && bytes[1] != '6'))
        throw IoError(path, "cannot decode image: only binary PGM and PPM (P5, P6) are read, not P1-P4");
    const bool colour = bytes[1] == '6';
    const NetpbmHeader h =
        NetpbmHeaderParser(path, bytes).parse(colour ? '6' : '5', colour ? "binary PPM" : "binary PGM");
    if (h.maxval < 1 || h.maxval > 65535)
        throw IoError(path, "maxval " + std::to_string(h.maxval) + " out of range (1..65535)");
    const int channels = colour ? 3 : 1, sample_bytes = h.maxval > 255 ? 2 : 1;
    requirePixelBytes(path, bytes, h, std::size_t(channels * sample_bytes));
    image.reset(Vec2i{h.width, h.height}, channels, sample_bytes, unsigned(h.maxval));
    const unsigned char* src = bytes.data() + h.data_offset;
    if (sample_bytes == 1) {
        std::memcpy(image.samples.data(), src, image.samples.size());
        return;
    }
    for (std::size_t i = 0; i < image.samples.size(); i += 2) {  // big-endian, as Netpbm defines
        const std::uint16_t v = std::uint16_t(src[i] << 8 | src[i + 1]);
        std::memcpy(&image.samples[i], &v, 2);
    }
}

// Decodes a file that passed requireImageFile and requirePlausibleImage.
void decode(const std::string& path, image_header::Format format, codecs::DecodedImage& image) {
    std::vector<unsigned char>& bytes = decodeScratch().bytes;
    readWholeFile(path, bytes);
    switch (format) {
        case image_header::Format::Png:
            return codecs::decodePng(path, bytes, image);
        case image_header::Format::Jpeg:
            return codecs::decodeJpeg(path, bytes, image);
        case image_header::Format::Tiff:
            return codecs::decodeTiff(path, bytes, image);
        case image_header::Format::Bmp:
            return codecs::decodeBmp(path, bytes, image);
        case image_header::Format::Netpbm:
            return decodeNetpbm(path, bytes, image);
        case image_header::Format::Unknown:
            break;
    }
    throw IoError(path, "cannot decode image: not a format VoxFuse reads");
}

// Encoded in memory and written through AtomicFile, which checks the flush and the close: a codec's
// own file writer might not, so a disk that fills during the last flush would leave a short image
// under its final name.
void writeEncoded(const std::string& path, const codecs::Bytes& bytes) {
    AtomicFile file(path);
    file.stream().write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    file.commit();
}

bool hasExtension(const std::string& path, const char* extension) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext == extension;
}

void requirePngName(const std::string& path, const char* what) {
    if (!hasExtension(path, ".png"))
        throw IoError(path, std::string(what) + " are written as PNG: the file name must end in .png");
}

}  // namespace

std::size_t readPPM(const std::string& path, Image<Vec4u8>& image) {
    requireImageFile(path);
    std::vector<unsigned char>& bytes = decodeScratch().bytes;
    readWholeFile(path, bytes);
    const NetpbmHeader h = NetpbmHeaderParser(path, bytes).parse('6', "binary PPM colour image");
    if (h.maxval < 1 || h.maxval > 255)
        throw IoError(path, "maxval " + std::to_string(h.maxval) +
                                " out of range: an 8-bit PPM needs 1..255 (16-bit PPM is not supported)");
    requirePixelBytes(path, bytes, h, 3);
    // Rescale so that maxval means full intensity, as the format defines (samples above maxval are
    // invalid: clamped rather than wrapped, and counted).
    std::uint8_t to8bit[256];
    for (unsigned v = 0; v < 256; ++v)
        to8bit[v] = std::uint8_t(std::min(255u, (v * 255u + unsigned(h.maxval) / 2) / unsigned(h.maxval)));
    image.resize(Vec2i{h.width, h.height});
    const unsigned char* src = bytes.data() + h.data_offset;
    Vec4u8* dst = image.host();
    std::size_t over_maxval = 0;
    const unsigned maxval = unsigned(h.maxval);
    for (std::size_t i = 0; i < image.pixelCount(); ++i, src += 3) {
        over_maxval += (src[0] > maxval) + (src[1] > maxval) + (src[2] > maxval);
        dst[i] = Vec4u8{to8bit[src[0]], to8bit[src[1]], to8bit[src[2]], 255};
    }
    return over_maxval;
}

Image<Vec4u8> readPPM(const std::string& path) {
    Image<Vec4u8> image;
    readPPM(path, image);
    return image;
}

std::size_t readPGM16(const std::string& path, Image<std::uint16_t>& image) {
    requireImageFile(path);
    std::vector<unsigned char>& bytes = decodeScratch().bytes;
    readWholeFile(path, bytes);
    const NetpbmHeader h = NetpbmHeaderParser(path, bytes).parse('5', "binary PGM depth image");
    if (h.maxval < 1 || h.maxval > 65535)
        throw IoError(path, "maxval " + std::to_string(h.maxval) + " out of range (1..65535)");
    if (h.maxval <= 255)
        throw IoError(path, "8-bit PGM (maxval " + std::to_string(h.maxval) +
                                "): expected a 16-bit depth PGM (maxval 256..65535)");
    requirePixelBytes(path, bytes, h, 2);
    image.resize(Vec2i{h.width, h.height});
    const unsigned char* src = bytes.data() + h.data_offset;
    std::uint16_t* dst = image.host();
    // Raw samples are kept as they are (not rescaled by maxval): they are depth units, not intensities.
    const unsigned maxval = unsigned(h.maxval);
    std::size_t over_maxval = 0;
    for (std::size_t i = 0; i < image.pixelCount(); ++i, src += 2) {
        const unsigned v = unsigned(src[0] << 8) | src[1];
        over_maxval += v > maxval;
        dst[i] = std::uint16_t(v > maxval ? 0u : v);
    }
    return over_maxval;
}

Image<std::uint16_t> readPGM16(const std::string& path) {
    Image<std::uint16_t> image;
    readPGM16(path, image);
    return image;
}

void writePPM(const std::string& path, const Image<Vec4u8>& rgb) {
    if (rgb.empty()) throw IoError(path, "cannot write an empty image");
    std::vector<unsigned char> data(rgb.pixelCount() * 3);
    const Vec4u8* src = rgb.host();
    for (std::size_t i = 0; i < rgb.pixelCount(); ++i) {
        data[3 * i] = src[i].x;
        data[3 * i + 1] = src[i].y;
        data[3 * i + 2] = src[i].z;
    }
    writeWholeFile(path, netpbmHeader("P6", rgb.size(), 255), data);
}

void writePGM16(const std::string& path, const Image<std::uint16_t>& depth) {
    if (depth.empty()) throw IoError(path, "cannot write an empty image");
    std::vector<unsigned char> data(depth.pixelCount() * 2);
    const std::uint16_t* src = depth.host();
    for (std::size_t i = 0; i < depth.pixelCount(); ++i) {
        data[2 * i] = static_cast<unsigned char>(src[i] >> 8);  // big-endian, as Netpbm defines
        data[2 * i + 1] = static_cast<unsigned char>(src[i] & 0xff);
    }
    writeWholeFile(path, netpbmHeader("P5", depth.size(), 65535), data);
}

namespace {

// 8-bit RGBA of any decoded image: grey is repeated, a missing alpha is opaque, other ranges are
// scaled so that maxval is 255 (samples above it, invalid, are full intensity).
void toRgba(const codecs::DecodedImage& image, Image<Vec4u8>& rgba) {
    rgba.resize(image.size);
    const int n = image.channels;
    const unsigned maxval = image.maxval;
    const auto to8 = [maxval](unsigned v) { return std::uint8_t(std::min(255u, (v * 255u + maxval / 2) / maxval)); };
    for (int y = 0; y < image.size.y; ++y) {
        Vec4u8* dst = &rgba.at(0, y);
        if (image.bytes_per_sample == 1 && maxval == 255 && n >= 3) {  // the common case, without scaling
            const std::uint8_t* src = image.row(y);
            for (int x = 0; x < image.size.x; ++x, src += n)
                dst[x] = Vec4u8{src[0], src[1], src[2], n == 4 ? src[3] : std::uint8_t(255)};
            continue;
        }
        for (int x = 0; x < image.size.x; ++x) {
            const std::uint8_t first = to8(image.sample(x, y, 0));
            if (n <= 2)
                dst[x] = Vec4u8{first, first, first, n == 2 ? to8(image.sample(x, y, 1)) : std::uint8_t(255)};
            else
                dst[x] = Vec4u8{first, to8(image.sample(x, y, 1)), to8(image.sample(x, y, 2)),
                                n == 4 ? to8(image.sample(x, y, 3)) : std::uint8_t(255)};
        }
    }
}

}  // namespace

void codecs::readImageFile(const std::string& path, DecodedImage& image) {
    requireImageFile(path);
    decode(path, requirePlausibleImage(path).format, image);
}

std::size_t readColorImage(const std::string& path, Image<Vec4u8>& rgba) {
    if (hasExtension(path, ".ppm")) return readPPM(path, rgba);
    requireImageFile(path);
    const image_header::Format format = requirePlausibleImage(path).format;
    if (format == image_header::Format::Jpeg) {  // straight into the frame's image
        std::vector<unsigned char>& bytes = decodeScratch().bytes;
        readWholeFile(path, bytes);
        codecs::decodeJpegToRgba(path, bytes, rgba);
        return 0;
    }
    codecs::DecodedImage& image = decodeScratch().color;
    decode(path, format, image);
    toRgba(image, rgba);
    return 0;
}

Image<Vec4u8> readColorImage(const std::string& path) {
    Image<Vec4u8> rgba;
    readColorImage(path, rgba);
    return rgba;
}

void readDepthPNG(const std::string& path, Image<std::uint16_t>& depth) {
    codecs::DecodedImage& image = decodeScratch().depth;
    codecs::readImageFile(path, image);
    if (image.channels != 1 || image.bytes_per_sample != 2)
        throw IoError(path, "expected a 16-bit single-channel depth PNG, got " + image.describe());
    depth.resize(image.size);
    std::memcpy(depth.host(), image.samples.data(), image.samples.size());
}

Image<std::uint16_t> readDepthPNG(const std::string& path) {
    Image<std::uint16_t> depth;
    readDepthPNG(path, depth);
    return depth;
}

void writePNG(const std::string& path, const Image<Vec4u8>& rgba) {
    if (rgba.empty()) throw IoError(path, "cannot write an empty image");
    requirePngName(path, "colour images");
    // Keep alpha only when it carries something, so ordinary colour frames stay plain RGB files.
    bool opaque = true;
    for (std::size_t i = 0; i < rgba.pixelCount() && opaque; ++i) opaque = rgba.host()[i].w == 255;
    if (!opaque) return writeEncoded(path, codecs::encodePng(path, rgba.size(), 4, 1, rgba.host()));
    std::vector<std::uint8_t> rgb(rgba.pixelCount() * 3);
    for (std::size_t i = 0; i < rgba.pixelCount(); ++i) std::memcpy(&rgb[3 * i], &rgba.host()[i], 3);
    writeEncoded(path, codecs::encodePng(path, rgba.size(), 3, 1, rgb.data()));
}

void writeDepthPNG(const std::string& path, const Image<std::uint16_t>& depth) {
    if (depth.empty()) throw IoError(path, "cannot write an empty image");
    requirePngName(path, "depth images");
    writeEncoded(path, codecs::encodePng(path, depth.size(), 1, 2, depth.host()));
}

// Class ids as the file stores them: the decoders never stretch a PGM's maxval or a 1, 2 or 4-bit
// PNG's range to 0..255 (a 1-bit mask's 1 stays class 1).
Image<ClassId> readLabelImage(const std::string& path, int ignore_id) {
    if (ignore_id < -1 || ignore_id > 65535)
        throw ConfigError("label ignore id " + std::to_string(ignore_id) +
                          " out of range: expected -1 (none) or 0..65535");
    codecs::DecodedImage image;
    codecs::readImageFile(path, image);
    const std::string requirement = "label images must be single-channel 8- or 16-bit class ids; ";
    // Palette images are expanded to colour, so their indices are lost: say what to do about it.
    if (image.channels != 1)
        throw IoError(path, requirement + "this one has " + std::to_string(image.channels) +
                                " channels (colour-coded or palette images must be converted to class ids first)");
    Image<ClassId> labels(image.size);
    for (int y = 0; y < image.size.y; ++y) {
        ClassId* dst = &labels.at(0, y);
        for (int x = 0; x < image.size.x; ++x) {
            const int id = int(image.sample(x, y, 0));
            dst[x] = (id == ignore_id || id == int(kNoLabel)) ? kNoLabel : ClassId(id);
        }
    }
    return labels;
}

}  // namespace voxfuse
