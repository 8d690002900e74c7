// Colour and depth frames as the sources read them: JPEG, PNG, TIFF, BMP, PPM (the format by content,
// except PPM by name); the first byte picks the file name.

#include "FuzzInput.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/ImageIO.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace voxfuse;
    if (size < 1) return 0;
    static const char* const kNames[] = {"colour.jpg", "colour.png", "colour.ppm", "depth.png"};
    const int kind = data[0] % 4;
    const std::string path = fuzz::writeInput(data + 1, size - 1, kNames[kind]);
    try {
        if (kind == 3)
            readDepthPNG(path);
        else
            readColorImage(path);
    } catch (const Error&) {
    }
    return 0;
}
