// PNG through libpng, from and to memory. libpng reports errors by longjmp: the functions that call
// into it (readPng, writePng) hold no object with a destructor between their setjmp and libpng, and
// the callbacks never throw.

#include <csetjmp>
#include <cstdio>
#include <cstring>

#include <png.h>
#include <zlib.h>

#include "ImageCodecs.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace codecs {

namespace {

// What libpng's callbacks share with the code that called libpng: plain data only.
struct PngContext {
    const unsigned char* data = nullptr;  // reading: the file
    std::size_t size = 0, position = 0;
    Bytes* out = nullptr;  // writing: the file being made
    bool out_of_memory = false;
    char message[256] = {};
};

// PNG's 16-bit samples are big-endian; DecodedImage's are the host's.
bool hostIsLittleEndian() {
    const std::uint16_t probe = 1;
    std::uint8_t first_byte;
    std::memcpy(&first_byte, &probe, 1);
    return first_byte == 1;
}

PngContext& contextOf(png_structp png) { return *static_cast<PngContext*>(png_get_error_ptr(png)); }

void onError(png_structp png, png_const_charp message) {
    std::snprintf(contextOf(png).message, sizeof contextOf(png).message, "%s", message);
    png_longjmp(png, 1);
}

// libpng warns where it has recovered (an ancillary chunk with a bad checksum, which it skips):
// the image is whole, and a library has no business writing to stderr.
void onWarning(png_structp, png_const_charp) {}

void readFromMemory(png_structp png, png_bytep into, png_size_t count) {
    PngContext& c = *static_cast<PngContext*>(png_get_io_ptr(png));
    if (c.size - c.position < count) png_error(png, "the file ends before the image does (truncated)");
    std::memcpy(into, c.data + c.position, count);
    c.position += count;
}

void writeToMemory(png_structp png, png_bytep from, png_size_t count) {
    PngContext& c = *static_cast<PngContext*>(png_get_io_ptr(png));
    try {
        c.out->insert(c.out->end(), from, from + count);
    } catch (...) {
        c.out_of_memory = true;
    }
    if (c.out_of_memory) png_error(png, "out of memory");
}

void flushMemory(png_structp) {}

// Decodes into `image`. False, with the reason in `context.message`, when libpng fails.
bool readPng(png_structp png, png_infop info, PngContext& context, DecodedImage& image, std::vector<png_bytep>& rows) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_set_read_fn(png, &context, readFromMemory);
    png_read_info(png, info);
    const int color_type = png_get_color_type(png, info);
    const int bit_depth = png_get_bit_depth(png, info);
    unsigned maxval = bit_depth == 16 ? 65535u : 255u;
    if (color_type == PNG_COLOR_TYPE_PALETTE) {
        png_set_palette_to_rgb(png);
        if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
    } else if (bit_depth < 8) {
        // Grey of 1, 2 or 4 bits: one byte per sample, as stored (a 1-bit mask's 1 stays 1).
        png_set_packing(png);
        maxval = (1u << bit_depth) - 1u;
    } else if (png_get_valid(png, info, PNG_INFO_tRNS)) {
        png_set_tRNS_to_alpha(png);
    }
    if (bit_depth == 16 && hostIsLittleEndian()) png_set_swap(png);
    png_set_interlace_handling(png);
    png_read_update_info(png, info);
    const Vec2i size{int(png_get_image_width(png, info)), int(png_get_image_height(png, info))};
    const int channels = png_get_channels(png, info);
    const int bytes_per_sample = png_get_bit_depth(png, info) == 16 ? 2 : 1;
    image.reset(size, channels, bytes_per_sample, maxval);
    if (png_get_rowbytes(png, info) != image.rowBytes()) png_error(png, "unexpected row layout after decoding");
    rows.resize(std::size_t(size.y));
    for (int y = 0; y < size.y; ++y) rows[std::size_t(y)] = image.row(y);
    png_read_image(png, rows.data());
    png_read_end(png, nullptr);
    return true;
}

bool writePng(png_structp png, png_infop info, PngContext& context, Vec2i size, int channels, int bytes_per_sample,
              std::vector<png_bytep>& rows) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_set_write_fn(png, &context, writeToMemory, flushMemory);
    static const int kColorType[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                     PNG_COLOR_TYPE_RGB_ALPHA};
    png_set_IHDR(png, info, png_uint_32(size.x), png_uint_32(size.y), bytes_per_sample * 8, kColorType[channels - 1],
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    // Fast rather than small: renders and depth maps are written every frame (the settings OpenCV
    // writes PNGs with by default).
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
    png_set_compression_level(png, Z_BEST_SPEED);
    png_set_compression_strategy(png, Z_RLE);
    png_write_info(png, info);
    if (bytes_per_sample == 2 && hostIsLittleEndian()) png_set_swap(png);
    png_write_image(png, rows.data());
    png_write_end(png, nullptr);
    return true;
}

}  // namespace

void decodePng(const std::string& path, const Bytes& file, DecodedImage& image) {
    PngContext context;
    context.data = file.data();
    context.size = file.size();
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &context, onError, onWarning);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    const bool started = info != nullptr;  // png_destroy_read_struct clears both pointers
    std::vector<png_bytep> rows;
    bool ok = false;
    try {
        ok = info && readPng(png, info, context, image, rows);
    } catch (...) {  // out of memory for the image
        png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
        throw;
    }
    png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
    if (!started) throw IoError(path, "cannot start the PNG decoder (out of memory)");
    if (!ok) throw IoError(path, std::string("cannot decode image: corrupt PNG: ") + context.message);
}

Bytes encodePng(const std::string& path, Vec2i size, int channels, int bytes_per_sample, const void* samples) {
    if (channels < 1 || channels > 4 || (bytes_per_sample != 1 && bytes_per_sample != 2) || size.x <= 0 || size.y <= 0)
        throw IoError(path, "cannot encode the image as PNG: no image, or a sample layout PNG does not have");
    Bytes out;
    PngContext context;
    context.out = &out;
    std::vector<png_bytep> rows(std::size_t(size.y));
    const std::size_t row_bytes = std::size_t(size.x) * std::size_t(channels) * std::size_t(bytes_per_sample);
    for (int y = 0; y < size.y; ++y)
        rows[std::size_t(y)] =
            const_cast<png_bytep>(static_cast<const png_byte*>(samples) + std::size_t(y) * row_bytes);
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &context, onError, onWarning);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    const bool started = info != nullptr;  // png_destroy_write_struct clears both pointers
    const bool ok = started && writePng(png, info, context, size, channels, bytes_per_sample, rows);
    png_destroy_write_struct(&png, info ? &info : nullptr);
    if (!ok)
        throw IoError(path,
                      std::string("cannot encode the image as PNG: ") + (started ? context.message : "out of memory"));
    return out;
}

}  // namespace codecs
}  // namespace voxfuse
