#include "DepthPackSource.h"

#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <filesystem>

#include "voxfuse/core/Error.h"
#include "voxfuse/io/CalibIO.h"
#include "voxfuse/io/TumSource.h"  // packs come from TUM folders: their frames meet ground truth as there

namespace fs = std::filesystem;

namespace voxfuse::app {
namespace {
constexpr char kMagic[8] = {'V', 'F', 'D', 'E', 'P', 'T', 'H', '1'};
constexpr int kMaxSide = 1 << 14;

std::uint32_t littleEndian32(const unsigned char* b) {
    return std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 | std::uint32_t(b[2]) << 16 | std::uint32_t(b[3]) << 24;
}
}  // namespace

struct DepthPackSource::Stream {
    gzFile file = nullptr;
    ~Stream() {
        if (file) gzclose(file);
    }
};

bool DepthPackSource::isDepthPack(const std::string& path) {
    return fs::is_regular_file(fs::path(path) / "depth.bin.gz");
}

DepthPackSource::DepthPackSource(const std::string& folder)
    : folder_(folder), depth_path_((fs::path(folder) / "depth.bin.gz").string()), stream_(std::make_unique<Stream>()) {
    calib_ = readCalib((fs::path(folder) / "calib.txt").string());
    const fs::path gt = fs::path(folder) / "groundtruth.txt";
    if (fs::exists(gt)) ground_truth_ = readTumTrajectory(gt.string());
    stream_->file = gzopen(depth_path_.c_str(), "rb");
    if (!stream_->file) throw IoError(depth_path_, "cannot open: " + std::string(std::strerror(errno)));
    unsigned char header[sizeof(kMagic) + 12];
    readExactly(header, sizeof(header), -1);
    if (std::memcmp(header, kMagic, sizeof(kMagic)) != 0)
        throw IoError(depth_path_, "not a VoxFuse depth pack (no VFDEPTH1 header)");
    const std::uint32_t width = littleEndian32(header + 8), height = littleEndian32(header + 12),
                        frames = littleEndian32(header + 16);
    if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide || frames > (1u << 24))
        throw IoError(depth_path_, "implausible header: " + std::to_string(width) + "x" + std::to_string(height) +
                                       ", " + std::to_string(frames) + " frames");
    width_ = int(width);
    height_ = int(height);
    frames_ = int(frames);
    if (calib_.depth.width != width_ || calib_.depth.height != height_)
        throw IoError(depth_path_, "frames of " + std::to_string(width_) + "x" + std::to_string(height_) +
                                       " but calib.txt says " + std::to_string(calib_.depth.width) + "x" +
                                       std::to_string(calib_.depth.height));
}

DepthPackSource::~DepthPackSource() = default;

void DepthPackSource::readExactly(void* dst, std::size_t bytes, int frame) {
    const int got = gzread(stream_->file, dst, unsigned(bytes));
    if (got == int(bytes)) return;
    int zlib_error = Z_OK;
    const char* message = gzerror(stream_->file, &zlib_error);
    throw IoError(depth_path_,
                  got < 0 || zlib_error != Z_OK ? std::string("corrupt: ") + message : "truncated: the file ends early",
                  frame);
}

bool DepthPackSource::next(RGBDFrame& frame) {
    if (next_ >= frames_) return false;
    const int index = next_;
    // A frame that cannot be read ends the pack: the stream has no way to skip to the next one.
    next_ = frames_;
    unsigned char stamp[8];
    readExactly(stamp, sizeof(stamp), index);
    std::uint64_t bits = std::uint64_t(littleEndian32(stamp)) | std::uint64_t(littleEndian32(stamp + 4)) << 32;
    double timestamp_s;
    std::memcpy(&timestamp_s, &bits, sizeof(timestamp_s));
    Image<std::uint16_t> depth(Vec2i{width_, height_});
    static_assert(sizeof(std::uint16_t) == 2, "raw depth samples are 16-bit");
    readExactly(depth.host(), depth.pixelCount() * 2, index);
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
    for (std::size_t i = 0; i < depth.pixelCount(); ++i)
        depth.host()[i] = std::uint16_t(depth.host()[i] << 8 | depth.host()[i] >> 8);
#endif
    next_ = index + 1;
    frame.index = index;
    frame.timestamp_s = timestamp_s;
    frame.rgb_timestamp_s = -1.0;
    frame.depth_raw = std::move(depth);
    frame.rgb = Image<Vec4u8>();
    frame.labels = Image<ClassId>();
    frame.depth_path = depth_path_;
    frame.T_world_camera_gt = Mat4f::identity();
    frame.has_ground_truth =
        interpolatePose(ground_truth_, timestamp_s, TumSource::kMaxTimeDifference_s, frame.T_world_camera_gt);
    return true;
}

std::string DepthPackSource::description() const {
    return "depth pack " + folder_ + " (" + std::to_string(frames_) + " frames of " + std::to_string(width_) + "x" +
           std::to_string(height_) + (ground_truth_.empty() ? ", no ground truth)" : ", ground truth)");
}

}  // namespace voxfuse::app
