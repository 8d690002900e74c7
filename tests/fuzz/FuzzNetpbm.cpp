// PPM colour and 16-bit PGM depth images: read, or refused with an error naming the file.

#include "FuzzInput.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/ImageIO.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace voxfuse;
    const std::string path = fuzz::writeInput(data, size, "frame.pnm");
    try {
        readPPM(path);
    } catch (const Error&) {
    }
    try {
        readPGM16(path);
    } catch (const Error&) {
    }
    return 0;
}
