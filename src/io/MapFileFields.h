#pragma once
// The map file's byte streams (io/MapFile.h): little-endian fields written and read in chunks, with a
// running CRC-32. Shared by the single map's and the submap set's readers and writers.

#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "voxfuse/core/Error.h"
#include "voxfuse/core/Math.h"
#include "voxfuse/io/AtomicFile.h"
#include "voxfuse/io/MapFile.h"

namespace voxfuse {
namespace mapfile {

constexpr std::size_t kChunkBytes = std::size_t(1) << 20;  // the body is streamed in pieces of about this size

// Little-endian fields into a buffer, flushed to the file in chunks.
class FieldWriter {
public:
    explicit FieldWriter(AtomicFile& file) : file_(file) {}
    void u8(std::uint8_t v) { buffer_.push_back(v); }
    void u16(std::uint16_t v) { bytes(v, 2); }
    void i16(std::int16_t v) { u16(std::uint16_t(v)); }
    void u32(std::uint32_t v) { bytes(v, 4); }
    void i32(std::int32_t v) { u32(std::uint32_t(v)); }
    void u64(std::uint64_t v) { bytes(v, 8); }
    void f32(float v) {
        std::uint32_t bits;
        std::memcpy(&bits, &v, 4);
        u32(bits);
    }
    void raw(const char* p, std::size_t n) { buffer_.insert(buffer_.end(), p, p + n); }
    // Sends the buffered bytes to the file, adding them to the checksum first when `checksummed`.
    void flush(bool checksummed = true) {
        if (checksummed) crc_ = crc32(crc_, buffer_.data(), unsigned(buffer_.size()));
        file_.stream().write(reinterpret_cast<const char*>(buffer_.data()), std::streamsize(buffer_.size()));
        file_.check();
        buffer_.clear();
    }
    void flushIfFull() {
        if (buffer_.size() >= kChunkBytes) flush();
    }
    std::size_t buffered() const { return buffer_.size(); }
    std::uint32_t crc() const { return std::uint32_t(crc_); }
    void resetCrc() { crc_ = crc32(0L, Z_NULL, 0); }

private:
    void bytes(std::uint64_t v, int n) {
        for (int i = 0; i < n; ++i) buffer_.push_back(std::uint8_t(v >> (8 * i)));
    }
    AtomicFile& file_;
    std::vector<std::uint8_t> buffer_;
    uLong crc_ = crc32(0L, Z_NULL, 0);
};

// Little-endian fields from the file, read in chunks.
class FieldReader {
public:
    FieldReader(std::ifstream& in, const std::string& path) : in_(in), path_(path) {}
    std::uint8_t u8() { return take(1)[0]; }
    std::uint16_t u16() { return std::uint16_t(bytes(2)); }
    std::int16_t i16() { return std::int16_t(u16()); }
    std::uint32_t u32() { return std::uint32_t(bytes(4)); }
    std::int32_t i32() { return std::int32_t(u32()); }
    std::uint64_t u64() { return bytes(8); }
    float f32() {
        const std::uint32_t bits = u32();
        float v;
        std::memcpy(&v, &bits, 4);
        return v;
    }
    void raw(char* p, std::size_t n) { std::memcpy(p, take(n), n); }
    // Whether the next bytes are `expected` (not taken: nothing is counted or consumed). False when
    // the file ends before them.
    bool nextBytesAre(const char* expected, std::size_t n) {
        if (pos_ + n > buffer_.size() && !tryRefill(n)) return false;
        return std::memcmp(buffer_.data() + pos_, expected, n) == 0;
    }
    // Makes `n` bytes available (from the file, in one piece) and counts them into the checksum.
    const std::uint8_t* take(std::size_t n) {
        if (pos_ + n > buffer_.size()) refill(n);
        const std::uint8_t* p = buffer_.data() + pos_;
        crc_ = crc32(crc_, p, unsigned(n));
        pos_ += n;
        taken_ += n;
        return p;
    }
    // Bytes taken so far, from the start of the file.
    std::uint64_t taken() const { return taken_; }
    // The file's size, or -1 when it has none (a pipe).
    std::int64_t fileBytes() const {
        std::error_code ec;
        const std::uintmax_t size = std::filesystem::file_size(path_, ec);
        return ec ? -1 : std::int64_t(size);
    }
    std::uint32_t crc() const { return std::uint32_t(crc_); }
    void resetCrc() { crc_ = crc32(0L, Z_NULL, 0); }
    // True when every byte of the file has been taken.
    bool atEnd() { return pos_ == buffer_.size() && in_.peek() == std::char_traits<char>::eof(); }
    [[noreturn]] void fail(const std::string& reason) const { throw IoError(path_, reason); }

private:
    std::uint64_t bytes(int n) {
        const std::uint8_t* p = take(std::size_t(n));
        std::uint64_t v = 0;
        for (int i = 0; i < n; ++i) v |= std::uint64_t(p[i]) << (8 * i);
        return v;
    }
    void refill(std::size_t n) {
        if (!tryRefill(n))
            fail("truncated: the file ends inside the map (" + std::to_string(taken_ + buffer_.size()) +
                 " bytes read)");
    }
    bool tryRefill(std::size_t n) {
        buffer_.erase(buffer_.begin(), buffer_.begin() + std::ptrdiff_t(pos_));
        pos_ = 0;
        const std::size_t want = std::max(n, kChunkBytes);
        const std::size_t have = buffer_.size();
        buffer_.resize(want);
        in_.read(reinterpret_cast<char*>(buffer_.data() + have), std::streamsize(want - have));
        buffer_.resize(have + std::size_t(in_.gcount()));
        return buffer_.size() >= n;
    }
    std::ifstream& in_;
    std::string path_;
    std::vector<std::uint8_t> buffer_;
    std::size_t pos_ = 0;
    std::uint64_t taken_ = 0;
    uLong crc_ = crc32(0L, Z_NULL, 0);
};

inline void writeMat(FieldWriter& w, const Mat4f& m) {
    for (float x : m.m) w.f32(x);
}
inline Mat4f readMat(FieldReader& r) {
    Mat4f m;
    for (float& x : m.m) x = r.f32();
    return m;
}

constexpr char kMapMagic[8] = {'V', 'F', 'M', 'A', 'P', '\r', '\n', '\x1a'};
constexpr char kSubmapsMagic[8] = {'V', 'F', 'S', 'U', 'B', 'M', 'A', 'P'};

// The header fields from the voxel type name to the record count (io/MapFile.h), shared by a single
// map's header and a map of submaps' (io/SubmapMapFile.h). `voxel_bytes` is the voxel record's size.
void writeHeaderFields(FieldWriter& w, const MapFileInfo& info, std::uint32_t voxel_bytes);
// Reads them and checks every one against what a map can hold (IoError naming the file otherwise).
MapFileInfo readHeaderFields(FieldReader& r);
// The record size of a voxel type by its name (0 when unknown).
std::uint32_t voxelRecordBytesByName(const std::string& voxel_type);

}  // namespace mapfile

struct MapFileWriter::Stream {
    explicit Stream(const std::string& path) : file(path), fields(file) {}
    AtomicFile file;
    mapfile::FieldWriter fields;
};

struct MapFileReader::Stream {
    Stream(const std::string& p, std::ifstream&& s) : path(p), in(std::move(s)), fields(in, path) {}
    std::string path;
    std::ifstream in;
    mapfile::FieldReader fields;
    bool pending = false;  // nextMapInfo() read `info`, whose map is read next
    MapFileInfo info;
};

}  // namespace voxfuse
