// The text files of a per-frame folder: the 4x4 pose files and the 3x3 intrinsics (K), read the way
// FrameFolderSource reads them, beside one real depth image. The first byte says which file the rest is.

#include <filesystem>

#include "FuzzInput.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/FrameFolderSource.h"
#include "voxfuse/io/ImageIO.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace voxfuse;
    if (size < 1) return 0;
    static const std::string folder = [] {
        const std::string f = fuzz::scratchFolder() + "/frames";
        std::filesystem::create_directories(f);
        Image<std::uint16_t> depth(Vec2i{8, 6});
        for (std::size_t i = 0; i < depth.pixelCount(); ++i) depth.host()[i] = std::uint16_t(1000 + i);
        writeDepthPNG(f + "/frame-000000.depth.png", depth);
        return f;
    }();
    const bool pose = data[0] & 1;
    static const std::uint8_t good_k[] = "4 0 3.5\n0 4 2.5\n0 0 1\n";
    static const std::uint8_t identity[] = "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
    const std::string k_file =
        fuzz::writeInput(pose ? good_k : data + 1, pose ? sizeof good_k - 1 : size - 1, "frames/intrinsics.K.txt");
    fuzz::writeInput(pose ? data + 1 : identity, pose ? size - 1 : sizeof identity - 1, "frames/frame-000000.pose.txt");
    try {
        FrameFolderSource source(folder);
        RGBDFrame frame;
        source.next(frame);
    } catch (const Error&) {
    }
    (void)k_file;
    return 0;
}
