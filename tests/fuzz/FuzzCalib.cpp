// calib.txt: any bytes are read or refused with an error; what is read writes and reads back the same.

#include <cstdlib>

#include "FuzzInput.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/CalibIO.h"

namespace {

bool same(const voxfuse::Intrinsics& a, const voxfuse::Intrinsics& b) {
    return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy && a.cx == b.cx && a.cy == b.cy;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace voxfuse;
    const std::string path = fuzz::writeInput(data, size, "calib.txt");
    RGBDCalib calib;
    try {
        calib = readCalib(path);
    } catch (const Error&) {
        return 0;
    }
    const std::string copy = fuzz::scratchFolder() + "/calib_written.txt";
    writeCalib(copy, calib);
    const RGBDCalib back = readCalib(copy);
    if (!same(back.rgb, calib.rgb) || !same(back.depth, calib.depth) || back.disparity.a != calib.disparity.a ||
        back.disparity.b != calib.disparity.b || back.rgb_distortion.k1 != calib.rgb_distortion.k1)
        std::abort();  // a calibration that does not survive its own file format
    return 0;
}
