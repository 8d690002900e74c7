// Image files. PPM/PGM are read and written by hand because InfiniTAM's depth PGMs are 16-bit
// big-endian and we want exact, explained errors for them; everything else goes through OpenCV,
// which stays hidden in this file.

#include "voxfuse/io/ImageIO.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <turbojpeg.h>

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

std::vector<unsigned char> readWholeFile(const std::string& path) {
    std::vector<unsigned char> bytes;
    readWholeFile(path, bytes);
    return bytes;
}

// What decoding a frame needs besides its image, kept per thread so that reading a sequence makes no
// megabyte allocation per frame. Buffers made and freed every frame fragment glibc's heap (once one
// is freed, later ones come from the heap rather than mmap, and the small long-lived allocations
// between them keep it from shrinking), so the peak memory of a long run grows. OpenCV decodes into
// the Mat it is given, reusing its memory when the size and type match, so depth and colour keep one
// Mat each: sharing one would change its type, and reallocate it, twice a frame.
struct DecodeScratch {
    std::vector<unsigned char> bytes;  // the file
    cv::Mat depth;                     // a decoded depth image
    cv::Mat color, converted;          // a decoded colour image; its 8-bit version where it had 16
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
// OpenCV

std::string describeMat(const cv::Mat& m) {
    std::string depth;
    switch (m.depth()) {
        case CV_8U:
            depth = "8-bit";
            break;
        case CV_8S:
            depth = "8-bit signed";
            break;
        case CV_16U:
            depth = "16-bit";
            break;
        case CV_16S:
            depth = "16-bit signed";
            break;
        case CV_32S:
            depth = "32-bit integer";
            break;
        case CV_32F:
            depth = "32-bit float";
            break;
        case CV_64F:
            depth = "64-bit float";
            break;
        default:
            depth = "unknown-depth";
            break;
    }
    return depth + " " + std::to_string(m.channels()) + "-channel";
}

// Only the formats VoxFuse reads reach a decoder, and only with a size a frame can have: OpenCV
// allocates what a header claims (up to 2^30 pixels) before it reads a pixel.
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

// Decodes a file that passed requireImageFile and requirePlausibleImage.
void decodeWithOpenCV(const std::string& path, cv::Mat& m) {
    std::vector<unsigned char>& bytes = decodeScratch().bytes;
    readWholeFile(path, bytes);
    try {
        cv::imdecode(bytes, cv::IMREAD_UNCHANGED, &m);
    } catch (const cv::Exception& e) {
        throw IoError(path, "cannot decode image: " + e.msg);
    }
    if (m.empty()) throw IoError(path, "cannot decode image (corrupt file or unsupported format)");
}

void readWithOpenCV(const std::string& path, cv::Mat& m) {
    requireImageFile(path);
    requirePlausibleImage(path);
    decodeWithOpenCV(path, m);
}

cv::Mat readWithOpenCV(const std::string& path) {
    cv::Mat m;
    readWithOpenCV(path, m);
    return m;
}

// Encoded in memory and written through AtomicFile, which checks the flush and the close: the codecs'
// own file writers do not, so a disk that fills during the last flush left a short image under its
// final name.
void writeWithOpenCV(const std::string& path, const cv::Mat& m) {
    std::vector<unsigned char> bytes;
    bool ok = false;
    std::string detail;
    try {
        ok = cv::imencode(std::filesystem::path(path).extension().string(), m, bytes);
    } catch (const cv::Exception& e) {
        detail = " (" + e.msg + ")";
    }
    if (!ok) throw IoError(path, "cannot encode the image: unknown format" + detail);
    AtomicFile file(path);
    file.stream().write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    file.commit();
}

template <typename T>
void copyMatToImage(const cv::Mat& m, Image<T>& image) {
    image.resize(Vec2i{m.cols, m.rows});
    const std::size_t row_bytes = std::size_t(m.cols) * sizeof(T);
    for (int y = 0; y < m.rows; ++y) std::memcpy(&image.at(0, y), m.ptr(y), row_bytes);
}

// The image as a cv::Mat header over its own memory: OpenCV writes into it without allocating.
cv::Mat matOver(Image<Vec4u8>& image) { return cv::Mat(image.height(), image.width(), CV_8UC4, image.host()); }

bool hasExtension(const std::string& path, const char* extension) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext == extension;
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

// JPEG through TurboJPEG rather than OpenCV: OpenCV decodes a truncated or damaged JPEG into a
// partly grey image and leaves only libjpeg's warning on stderr; here a warning is an error. CMYK
// JPEGs (TurboJPEG does not convert them to RGB) go to OpenCV. False: not decoded here.
bool readJpeg(const std::string& path, Image<Vec4u8>& image) {
    std::vector<unsigned char>& bytes = decodeScratch().bytes;
    readWholeFile(path, bytes);
    const std::unique_ptr<void, int (*)(tjhandle)> tj(tjInitDecompress(), tjDestroy);
    if (!tj) throw IoError(path, "cannot start the JPEG decoder");
    int width = 0, height = 0, subsampling = 0, colorspace = 0;
    if (tjDecompressHeader3(tj.get(), bytes.data(), static_cast<unsigned long>(bytes.size()), &width, &height,
                            &subsampling, &colorspace) != 0)
        throw IoError(path, std::string("corrupt JPEG: ") + tjGetErrorStr2(tj.get()));
    if (colorspace == TJCS_CMYK || colorspace == TJCS_YCCK) return false;
    if (width <= 0 || height <= 0) throw IoError(path, "corrupt JPEG: the header gives no image size");
    if (double(width) * double(height) > kMaxImagePixels)
        throw IoError(path, "the JPEG says it is " + std::to_string(width) + "x" + std::to_string(height) +
                                " pixels: too large for an image of a frame (corrupt header?)");
    image.resize(Vec2i{width, height});
    if (tjDecompress2(tj.get(), bytes.data(), static_cast<unsigned long>(bytes.size()),
                      reinterpret_cast<unsigned char*>(image.host()), width, 0, height, TJPF_RGBA,
                      TJFLAG_STOPONWARNING) != 0)
        throw IoError(path,
                      std::string("corrupt JPEG: ") + tjGetErrorStr2(tj.get()) + " (the file is damaged or truncated)");
    return true;
}

}  // namespace

std::size_t readColorImage(const std::string& path, Image<Vec4u8>& rgba) {
    if (hasExtension(path, ".ppm")) return readPPM(path, rgba);
    requireImageFile(path);
    if (requirePlausibleImage(path).format == image_header::Format::Jpeg && readJpeg(path, rgba)) return 0;
    DecodeScratch& scratch = decodeScratch();
    decodeWithOpenCV(path, scratch.color);
    const cv::Mat* m = &scratch.color;
    if (m->depth() == CV_16U) {
        m->convertTo(scratch.converted, CV_8U, 1.0 / 257.0);  // 65535 -> 255
        m = &scratch.converted;
    } else if (m->depth() != CV_8U) {
        throw IoError(path, "unsupported colour image: " + describeMat(*m) + " (expected 8- or 16-bit)");
    }
    const int channels = m->channels();
    const int to_rgba = channels == 1   ? cv::COLOR_GRAY2RGBA
                        : channels == 3 ? cv::COLOR_BGR2RGBA
                        : channels == 4 ? cv::COLOR_BGRA2RGBA
                                        : -1;
    if (to_rgba < 0)
        throw IoError(path, "unsupported colour image: " + describeMat(*m) + " (expected 1, 3 or 4 channels)");
    rgba.resize(Vec2i{m->cols, m->rows});
    cv::Mat into = matOver(rgba);
    cv::cvtColor(*m, into, to_rgba);
    return 0;
}

Image<Vec4u8> readColorImage(const std::string& path) {
    Image<Vec4u8> rgba;
    readColorImage(path, rgba);
    return rgba;
}

void readDepthPNG(const std::string& path, Image<std::uint16_t>& depth) {
    cv::Mat& m = decodeScratch().depth;
    readWithOpenCV(path, m);
    if (m.type() != CV_16UC1) throw IoError(path, "expected a 16-bit single-channel depth PNG, got " + describeMat(m));
    copyMatToImage(m, depth);
}

Image<std::uint16_t> readDepthPNG(const std::string& path) {
    Image<std::uint16_t> depth;
    readDepthPNG(path, depth);
    return depth;
}

void writePNG(const std::string& path, const Image<Vec4u8>& rgba) {
    if (rgba.empty()) throw IoError(path, "cannot write an empty image");
    const cv::Mat wrapped(rgba.height(), rgba.width(), CV_8UC4, const_cast<Vec4u8*>(rgba.host()));
    // Keep alpha only when it carries something, so ordinary colour frames stay plain RGB files.
    bool opaque = true;
    for (std::size_t i = 0; i < rgba.pixelCount() && opaque; ++i) opaque = rgba.host()[i].w == 255;
    cv::Mat bgr;
    cv::cvtColor(wrapped, bgr, opaque ? cv::COLOR_RGBA2BGR : cv::COLOR_RGBA2BGRA);
    writeWithOpenCV(path, bgr);
}

void writeDepthPNG(const std::string& path, const Image<std::uint16_t>& depth) {
    if (depth.empty()) throw IoError(path, "cannot write an empty image");
    if (!hasExtension(path, ".png"))
        throw IoError(path, "depth images are written as 16-bit PNG: the file name must end in .png");
    const cv::Mat wrapped(depth.height(), depth.width(), CV_16UC1, const_cast<std::uint16_t*>(depth.host()));
    writeWithOpenCV(path, wrapped);
}

namespace {

// Class ids as the file stores them. OpenCV rescales what it reads in two cases that would change
// ids silently, so those are read here: binary PGMs (OpenCV stretches maxval < 255 to 0..255) and
// grey PNGs of 1, 2 or 4 bits (libpng expands them to 0..255: a 1-bit 1 becomes 255).
cv::Mat readRawClassIds(const std::string& path) {
    if (hasExtension(path, ".pgm")) {
        requireImageFile(path);
        const auto bytes = readWholeFile(path);
        const NetpbmHeader h = NetpbmHeaderParser(path, bytes).parse('5', "binary PGM label image");
        if (h.maxval < 1 || h.maxval > 65535)
            throw IoError(path, "maxval " + std::to_string(h.maxval) + " out of range (1..65535)");
        const bool wide = h.maxval > 255;  // two bytes per sample, big-endian
        requirePixelBytes(path, bytes, h, wide ? 2 : 1);
        cv::Mat m(h.height, h.width, wide ? CV_16UC1 : CV_8UC1);
        const unsigned char* src = bytes.data() + h.data_offset;
        for (int y = 0; y < h.height; ++y)
            for (int x = 0; x < h.width; ++x, src += wide ? 2 : 1) {
                if (wide)
                    m.at<std::uint16_t>(y, x) = std::uint16_t((src[0] << 8) | src[1]);
                else
                    m.at<std::uint8_t>(y, x) = src[0];
            }
        return m;
    }
    cv::Mat m = readWithOpenCV(path);
    // PNG: signature, IHDR length and type, width, height, then bit depth (byte 24) and colour type (25).
    std::ifstream in(path, std::ios::binary);
    unsigned char head[26] = {};
    const bool png = in.read(reinterpret_cast<char*>(head), sizeof head) &&
                     std::memcmp(head, "\x89PNG\r\n\x1a\n", 8) == 0 && std::memcmp(head + 12, "IHDR", 4) == 0;
    const int bits = head[24];
    const bool grey = head[25] == 0;
    if (png && grey && (bits == 1 || bits == 2 || bits == 4) && m.type() == CV_8UC1)
        m /= 255 / ((1 << bits) - 1);  // exact: 255, 85, 17
    return m;
}

}  // namespace

Image<ClassId> readLabelImage(const std::string& path, int ignore_id) {
    if (ignore_id < -1 || ignore_id > 65535)
        throw ConfigError("label ignore id " + std::to_string(ignore_id) +
                          " out of range: expected -1 (none) or 0..65535");
    const cv::Mat m = readRawClassIds(path);
    const std::string requirement = "label images must be single-channel 8- or 16-bit class ids; ";
    // IMREAD_UNCHANGED expands palette PNGs to BGR, so their indices are lost: say what to do about it.
    if (m.channels() != 1)
        throw IoError(path, requirement + "this one has " + std::to_string(m.channels()) +
                                " channels (colour-coded or palette images must be converted to class ids first)");
    if (m.depth() != CV_8U && m.depth() != CV_16U) throw IoError(path, requirement + "this one is " + describeMat(m));
    Image<ClassId> labels(Vec2i{m.cols, m.rows});
    const bool eight_bit = m.depth() == CV_8U;
    for (int y = 0; y < m.rows; ++y) {
        ClassId* dst = &labels.at(0, y);
        for (int x = 0; x < m.cols; ++x) {
            const int id = eight_bit ? int(m.ptr<std::uint8_t>(y)[x]) : int(m.ptr<std::uint16_t>(y)[x]);
            dst[x] = (id == ignore_id || id == int(kNoLabel)) ? kNoLabel : ClassId(id);
        }
    }
    return labels;
}

}  // namespace voxfuse
