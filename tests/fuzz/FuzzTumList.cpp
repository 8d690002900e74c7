// TUM image lists (rgb.txt, depth.txt, label lists): "timestamp filename" lines.

#include "FuzzInput.h"
#include "io/FrameReading.h"
#include "voxfuse/core/Error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace voxfuse;
    const std::string path = fuzz::writeInput(data, size, "rgb.txt");
    try {
        int missing = 0;
        frame_reading::readTimestampedImageList(path, missing);
    } catch (const Error&) {
    }
    return 0;
}
