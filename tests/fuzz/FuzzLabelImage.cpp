// Label images (one class id per pixel) as PNG, PGM or TIFF; the first byte picks the file type.

#include "FuzzInput.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/ImageIO.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace voxfuse;
    if (size < 1) return 0;
    static const char* const kNames[] = {"labels.png", "labels.pgm", "labels.tif"};
    const std::string path = fuzz::writeInput(data + 1, size - 1, kNames[data[0] % 3]);
    try {
        readLabelImage(path, data[0] & 0x80 ? 255 : -1);
    } catch (const Error&) {
    }
    return 0;
}
