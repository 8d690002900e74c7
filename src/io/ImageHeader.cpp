#include "ImageHeader.h"

#include <cctype>
#include <cstring>
#include <fstream>
#include <vector>

namespace voxfuse {
namespace image_header {

namespace {

constexpr std::size_t kHeadBytes = 4096;

std::uint32_t be32(const unsigned char* p) {
    return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) | p[3];
}
std::uint16_t be16(const unsigned char* p) { return std::uint16_t((p[0] << 8) | p[1]); }
std::uint32_t le32(const unsigned char* p) {
    return (std::uint32_t(p[3]) << 24) | (std::uint32_t(p[2]) << 16) | (std::uint32_t(p[1]) << 8) | p[0];
}

// PNG: width and height are the first fields of the IHDR chunk.
void readPng(const std::vector<unsigned char>& b, Header& h) {
    if (b.size() >= 24 && std::memcmp(b.data() + 12, "IHDR", 4) == 0) {
        h.width = be32(b.data() + 16);
        h.height = be32(b.data() + 20);
    }
}

// JPEG: the first start-of-frame marker (SOF0..SOF15 but DHT, JPG and DAC) holds height and width.
// Segments are followed through the whole file, not only its head: metadata (EXIF, comments, up to
// 64 KB each) may come first, and a size not found would let any size through to the decoder.
void readJpeg(std::ifstream& in, Header& h) {
    std::uint64_t at = 2;
    unsigned char m[9];
    for (int segments = 0; segments < (1 << 16); ++segments) {
        in.clear();
        if (!in.seekg(std::streamoff(at)) || !in.read(reinterpret_cast<char*>(m), 9) || m[0] != 0xff) return;
        const unsigned char marker = m[1];
        if (marker == 0xff) {  // fill byte
            ++at;
            continue;
        }
        if (marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 && marker != 0xcc) {
            h.height = be16(m + 5);
            h.width = be16(m + 7);
            return;
        }
        if (marker == 0xda) return;  // start of scan: no frame header before the image data
        const std::uint16_t length = be16(m + 2);
        if (length < 2) return;
        at += 2 + length;
    }
}

// Netpbm P1..P6: magic, then width, height (and maxval) as decimal numbers with '#' comments.
void readNetpbm(const std::vector<unsigned char>& b, Header& h) {
    std::size_t i = 2;
    long long values[3] = {-1, -1, 1};
    const int kind = b[1] - '0';
    const int count = kind == 1 || kind == 4 ? 2 : 3;
    for (int v = 0; v < count; ++v) {
        for (;;) {
            while (i < b.size() && std::isspace(b[i])) ++i;
            if (i < b.size() && b[i] == '#')
                while (i < b.size() && b[i] != '\n') ++i;
            else
                break;
        }
        long long value = 0;
        std::size_t digits = 0;
        while (i < b.size() && std::isdigit(b[i]) && digits < 12) value = value * 10 + (b[i++] - '0'), ++digits;
        if (digits == 0) return;
        values[v] = value;
    }
    h.width = values[0];
    h.height = values[1];
    const std::uint64_t channels = kind == 3 || kind == 6 ? 3 : 1, sample_bytes = values[2] > 255 ? 2 : 1;
    if (kind >= 5) h.minimum_bytes = i + 1 + std::uint64_t(h.width) * std::uint64_t(h.height) * channels * sample_bytes;
}

// BMP: a signed width and height (negative: rows top down) in the info header.
void readBmp(const std::vector<unsigned char>& b, Header& h) {
    if (b.size() < 26) return;
    const std::int32_t w = std::int32_t(le32(b.data() + 18)), hh = std::int32_t(le32(b.data() + 22));
    h.width = w < 0 ? -std::int64_t(w) : w;
    h.height = hh < 0 ? -std::int64_t(hh) : hh;
}

// TIFF: the ImageWidth (256) and ImageLength (257) entries of the first directory, wherever it is.
void readTiff(std::ifstream& in, const std::vector<unsigned char>& b, Header& h) {
    const bool little = b[0] == 'I';
    auto u16 = [&](const unsigned char* p) { return little ? std::uint16_t(p[0] | (p[1] << 8)) : be16(p); };
    auto u32 = [&](const unsigned char* p) { return little ? le32(p) : be32(p); };
    const std::uint32_t directory = u32(b.data() + 4);
    unsigned char count_bytes[2];
    in.clear();
    if (!in.seekg(directory) || !in.read(reinterpret_cast<char*>(count_bytes), 2)) return;
    const std::uint16_t count = u16(count_bytes);
    std::vector<unsigned char> entries(std::size_t(count) * 12);
    if (!in.read(reinterpret_cast<char*>(entries.data()), std::streamsize(entries.size()))) return;
    for (std::size_t e = 0; e < count; ++e) {
        const unsigned char* entry = entries.data() + 12 * e;
        const std::uint16_t tag = u16(entry), type = u16(entry + 2);
        const std::int64_t value = type == 3 ? u16(entry + 8) : u32(entry + 8);  // SHORT or LONG
        if (tag == 256) h.width = value;
        if (tag == 257) h.height = value;
    }
}

}  // namespace

Header read(const std::string& path) {
    Header h;
    std::ifstream in(path, std::ios::binary);
    std::vector<unsigned char> b(kHeadBytes);
    in.read(reinterpret_cast<char*>(b.data()), std::streamsize(b.size()));
    b.resize(std::size_t(in.gcount()));
    if (b.size() >= 8 && std::memcmp(b.data(), "\x89PNG\r\n\x1a\n", 8) == 0) {
        h.format = Format::Png;
        readPng(b, h);
    } else if (b.size() >= 3 && b[0] == 0xff && b[1] == 0xd8 && b[2] == 0xff) {
        h.format = Format::Jpeg;
        readJpeg(in, h);
    } else if (b.size() >= 3 && b[0] == 'P' && b[1] >= '1' && b[1] <= '6' && std::isspace(b[2])) {
        h.format = Format::Netpbm;
        readNetpbm(b, h);
    } else if (b.size() >= 8 && (std::memcmp(b.data(), "II*\0", 4) == 0 || std::memcmp(b.data(), "MM\0*", 4) == 0)) {
        h.format = Format::Tiff;
        readTiff(in, b, h);
    } else if (b.size() >= 2 && b[0] == 'B' && b[1] == 'M') {
        h.format = Format::Bmp;
        readBmp(b, h);
    }
    return h;
}

const char* name(Format format) {
    switch (format) {
        case Format::Png:
            return "PNG";
        case Format::Jpeg:
            return "JPEG";
        case Format::Netpbm:
            return "PPM/PGM";
        case Format::Tiff:
            return "TIFF";
        case Format::Bmp:
            return "BMP";
        case Format::Unknown:
            break;
    }
    return "unknown format";
}

}  // namespace image_header
}  // namespace voxfuse
