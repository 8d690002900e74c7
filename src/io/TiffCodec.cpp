// TIFF through libtiff, from memory. Grey and RGB(A) images of 1 to 16-bit unsigned samples in strips
// (what cameras and label tools write) are read as stored; any other layout libtiff can render
// (palette, YCbCr, CMYK, tiles...) comes as 8-bit RGBA. Float samples are refused: VoxFuse reads
// depth as integer units and labels as integer ids.

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <memory>

#include <tiffio.h>

#include "ImageCodecs.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace codecs {

namespace {

struct MemoryFile {
    const unsigned char* data;
    toff_t size, position;
    std::string first_error;  // libtiff's first error message; later ones follow from it
};

tmsize_t readMemory(thandle_t handle, void* into, tmsize_t count) {
    MemoryFile& f = *static_cast<MemoryFile*>(handle);
    const toff_t n = std::min<toff_t>(toff_t(count), f.size - std::min(f.position, f.size));
    std::memcpy(into, f.data + f.position, std::size_t(n));
    f.position += n;
    return tmsize_t(n);
}
tmsize_t writeNothing(thandle_t, void*, tmsize_t) { return 0; }
toff_t seekMemory(thandle_t handle, toff_t offset, int whence) {
    MemoryFile& f = *static_cast<MemoryFile*>(handle);
    const toff_t base = whence == SEEK_CUR ? f.position : whence == SEEK_END ? f.size : 0;
    f.position = base + offset;
    return f.position;
}
int closeNothing(thandle_t) { return 0; }
toff_t sizeOfMemory(thandle_t handle) { return static_cast<MemoryFile*>(handle)->size; }
int mapNothing(thandle_t, void**, toff_t*) { return 0; }
void unmapNothing(thandle_t, void*, toff_t) {}

int onError(TIFF*, void* user_data, const char* module, const char* format, va_list args) {
    MemoryFile& f = *static_cast<MemoryFile*>(user_data);
    if (f.first_error.empty()) {
        char message[512];
        std::vsnprintf(message, sizeof message, format, args);
        f.first_error = std::string(module ? module : "libtiff") + ": " + message;
    }
    return 1;  // handled: nothing reaches libtiff's default handler, which writes to stderr
}
// Warnings (an unknown tag, a deprecated layout) leave the image whole.
int onWarning(TIFF*, void*, const char*, const char*, va_list) { return 1; }

// 1, 2 or 4-bit samples, most significant first, into one byte each.
void unpackSamples(const std::uint8_t* packed, int count, int bits, std::uint8_t* out) {
    const unsigned mask = (1u << bits) - 1u;
    for (int i = 0; i < count; ++i) {
        const int bit = i * bits;
        out[i] = std::uint8_t((packed[bit / 8] >> (8 - bits - bit % 8)) & mask);
    }
}

}  // namespace

void decodeTiff(const std::string& path, const Bytes& file, DecodedImage& image) {
    MemoryFile memory{file.data(), toff_t(file.size()), 0, {}};
    const std::unique_ptr<TIFFOpenOptions, void (*)(TIFFOpenOptions*)> options(TIFFOpenOptionsAlloc(),
                                                                               TIFFOpenOptionsFree);
    if (!options) throw IoError(path, "cannot start the TIFF decoder (out of memory)");
    TIFFOpenOptionsSetErrorHandlerExtR(options.get(), onError, &memory);
    TIFFOpenOptionsSetWarningHandlerExtR(options.get(), onWarning, &memory);
    // A damaged directory can ask for any strip size; no frame's strip needs more.
    TIFFOpenOptionsSetMaxSingleMemAlloc(options.get(), tmsize_t(1) << 30);
    const std::unique_ptr<TIFF, void (*)(TIFF*)> tiff(
        TIFFClientOpenExt(path.c_str(), "rm", &memory, readMemory, writeNothing, seekMemory, closeNothing, sizeOfMemory,
                          mapNothing, unmapNothing, options.get()),
        TIFFClose);
    const auto fail = [&](const std::string& reason) {
        throw IoError(path, "cannot decode image: " + reason +
                                (memory.first_error.empty() ? "" : " (" + memory.first_error + ")"));
    };
    if (!tiff) fail("corrupt TIFF");
    std::uint32_t width = 0, height = 0;
    std::uint16_t samples_per_pixel = 1, bits = 1, sample_format = SAMPLEFORMAT_UINT, photometric = 0,
                  planar = PLANARCONFIG_CONTIG;
    TIFFGetField(tiff.get(), TIFFTAG_IMAGEWIDTH, &width);
    TIFFGetField(tiff.get(), TIFFTAG_IMAGELENGTH, &height);
    TIFFGetFieldDefaulted(tiff.get(), TIFFTAG_SAMPLESPERPIXEL, &samples_per_pixel);
    TIFFGetFieldDefaulted(tiff.get(), TIFFTAG_BITSPERSAMPLE, &bits);
    TIFFGetFieldDefaulted(tiff.get(), TIFFTAG_SAMPLEFORMAT, &sample_format);
    TIFFGetFieldDefaulted(tiff.get(), TIFFTAG_PLANARCONFIG, &planar);
    if (!TIFFGetField(tiff.get(), TIFFTAG_PHOTOMETRIC, &photometric)) photometric = PHOTOMETRIC_MINISBLACK;
    if (width == 0 || height == 0) fail("the TIFF has no image size");
    if (sample_format == SAMPLEFORMAT_IEEEFP)
        fail(std::to_string(bits) + "-bit float TIFF: VoxFuse reads integer samples (depth in units, class ids)");
    if (sample_format != SAMPLEFORMAT_UINT) fail("signed-integer TIFF: VoxFuse reads unsigned samples");
    const Vec2i size{int(width), int(height)};

    const bool grey = photometric == PHOTOMETRIC_MINISBLACK && (samples_per_pixel == 1 || samples_per_pixel == 2);
    const bool rgb = photometric == PHOTOMETRIC_RGB && (samples_per_pixel == 3 || samples_per_pixel == 4);
    const bool as_stored =
        (grey || rgb) && (planar == PLANARCONFIG_CONTIG || samples_per_pixel == 1) && !TIFFIsTiled(tiff.get()) &&
        (bits == 8 || bits == 16 || (bits < 8 && samples_per_pixel == 1 && (bits == 1 || bits == 2 || bits == 4)));
    if (as_stored) {
        const int bytes_per_sample = bits == 16 ? 2 : 1;
        image.reset(size, samples_per_pixel, bytes_per_sample, (1u << bits) - 1u);
        std::vector<std::uint8_t> packed(bits < 8 ? std::size_t(TIFFScanlineSize(tiff.get())) : 0);
        for (int y = 0; y < size.y; ++y) {
            void* into = bits < 8 ? static_cast<void*>(packed.data()) : static_cast<void*>(image.row(y));
            if (TIFFReadScanline(tiff.get(), into, std::uint32_t(y), 0) < 0)
                fail("corrupt TIFF: row " + std::to_string(y) + " cannot be read");
            if (bits < 8) unpackSamples(packed.data(), size.x, bits, image.row(y));
        }
        return;
    }
    char why[1024] = {};
    if (!TIFFRGBAImageOK(tiff.get(), why)) fail(std::string("a TIFF layout VoxFuse does not read: ") + why);
    std::vector<std::uint32_t> abgr(std::size_t(size.x) * std::size_t(size.y));
    if (!TIFFReadRGBAImageOriented(tiff.get(), width, height, abgr.data(), ORIENTATION_TOPLEFT, 0))
        fail("corrupt TIFF");
    image.reset(size, 4, 1, 255);
    std::uint8_t* out = image.samples.data();
    for (const std::uint32_t p : abgr) {
        *out++ = std::uint8_t(TIFFGetR(p));
        *out++ = std::uint8_t(TIFFGetG(p));
        *out++ = std::uint8_t(TIFFGetB(p));
        *out++ = std::uint8_t(TIFFGetA(p));
    }
}

}  // namespace codecs
}  // namespace voxfuse
