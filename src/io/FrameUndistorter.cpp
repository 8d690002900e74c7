// Lens undistortion of raw frames through lookup maps computed once per camera: for each pixel of
// the ideal pinhole image, where the lens put it in the raw image.

#include "voxfuse/io/FrameUndistorter.h"

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "voxfuse/core/Error.h"

namespace voxfuse {

struct FrameUndistorter::Maps {
    Vec2i size{0, 0};
    std::vector<Vec2f> raw_position;  // per ideal pixel, row by row: its position in the raw image
};

namespace {

std::string sizeText(Vec2i size) { return std::to_string(size.x) + "x" + std::to_string(size.y); }

// Each pixel from the raw pixel nearest to its raw position; `outside` where that is off the image.
template <typename T>
void resampleNearest(const std::vector<Vec2f>& raw_position, const Image<T>& raw, Image<T>& out, T outside) {
    const Vec2i size = raw.size();
    for (int y = 0; y < size.y; ++y)
        for (int x = 0; x < size.x; ++x) {
            const Vec2f p = raw_position[std::size_t(y) * std::size_t(size.x) + std::size_t(x)];
            const int rx = int(std::lround(p.x)), ry = int(std::lround(p.y));
            out.at(x, y) = rx >= 0 && ry >= 0 && rx < size.x && ry < size.y ? raw.at(rx, ry) : outside;
        }
}

// Bilinear between the four raw pixels around each raw position; those off the image count as 0.
void resampleBilinear(const std::vector<Vec2f>& raw_position, const Image<Vec4u8>& raw, Image<Vec4u8>& out) {
    const Vec2i size = raw.size();
    const auto pixel = [&](int x, int y) {
        return x >= 0 && y >= 0 && x < size.x && y < size.y ? raw.at(x, y) : Vec4u8{0, 0, 0, 0};
    };
    for (int y = 0; y < size.y; ++y)
        for (int x = 0; x < size.x; ++x) {
            const Vec2f p = raw_position[std::size_t(y) * std::size_t(size.x) + std::size_t(x)];
            const float fx0 = std::floor(p.x), fy0 = std::floor(p.y);
            if (!(fx0 >= -1.f && fy0 >= -1.f && fx0 < float(size.x) && fy0 < float(size.y))) {  // NaN too
                out.at(x, y) = Vec4u8{0, 0, 0, 0};
                continue;
            }
            const int x0 = int(fx0), y0 = int(fy0);
            const float ax = p.x - fx0, ay = p.y - fy0;
            const Vec4u8 c00 = pixel(x0, y0), c10 = pixel(x0 + 1, y0), c01 = pixel(x0, y0 + 1),
                         c11 = pixel(x0 + 1, y0 + 1);
            const auto blend = [&](std::uint8_t v00, std::uint8_t v10, std::uint8_t v01, std::uint8_t v11) {
                const float top = float(v00) + ax * (float(v10) - float(v00));
                const float bottom = float(v01) + ax * (float(v11) - float(v01));
                return std::uint8_t(std::lround(top + ay * (bottom - top)));
            };
            out.at(x, y) = Vec4u8{blend(c00.x, c10.x, c01.x, c11.x), blend(c00.y, c10.y, c01.y, c11.y),
                                  blend(c00.z, c10.z, c01.z, c11.z), blend(c00.w, c10.w, c01.w, c11.w)};
        }
}

}  // namespace

std::unique_ptr<FrameUndistorter::Maps> FrameUndistorter::makeMaps(const Intrinsics& k, const LensDistortion& d) {
    if (!d.any()) return nullptr;
    if (!k.valid()) throw ConfigError("FrameUndistorter: a camera with lens distortion has invalid intrinsics");
    auto maps = std::make_unique<FrameUndistorter::Maps>();
    maps->size = k.size();
    maps->raw_position.resize(std::size_t(k.width) * std::size_t(k.height));
    // The same intrinsics in and out: the result is the ideal pinhole image of the calibrated camera.
    for (int v = 0; v < k.height; ++v)
        for (int u = 0; u < k.width; ++u) {
            const double x = (u - double(k.cx)) / k.fx, y = (v - double(k.cy)) / k.fy;
            const double r2 = x * x + y * y;
            const double radial = 1.0 + r2 * (d.k1 + r2 * (d.k2 + r2 * double(d.k3)));
            const double xd = x * radial + 2.0 * d.p1 * x * y + d.p2 * (r2 + 2.0 * x * x);
            const double yd = y * radial + d.p1 * (r2 + 2.0 * y * y) + 2.0 * d.p2 * x * y;
            maps->raw_position[std::size_t(v) * std::size_t(k.width) + std::size_t(u)] =
                Vec2f{float(k.fx * xd + k.cx), float(k.fy * yd + k.cy)};
        }
    return maps;
}

FrameUndistorter::FrameUndistorter(const RGBDCalib& calib)
    : rgb_maps_(makeMaps(calib.rgb, calib.rgb_distortion)),
      depth_maps_(makeMaps(calib.depth, calib.depth_distortion)),
      undistorted_(calib),
      label_distortion_(calib.labelDistortion()) {
    undistorted_.rgb_distortion = LensDistortion{};
    undistorted_.depth_distortion = LensDistortion{};
}

FrameUndistorter::~FrameUndistorter() = default;
FrameUndistorter::FrameUndistorter(FrameUndistorter&& other) noexcept
    : rgb_maps_(std::move(other.rgb_maps_)),
      depth_maps_(std::move(other.depth_maps_)),
      undistorted_(other.undistorted_),
      label_distortion_(other.label_distortion_),
      label_maps_(std::move(other.label_maps_)) {}

FrameUndistorter& FrameUndistorter::operator=(FrameUndistorter&& other) noexcept {
    rgb_maps_ = std::move(other.rgb_maps_);
    depth_maps_ = std::move(other.depth_maps_);
    undistorted_ = other.undistorted_;
    label_distortion_ = other.label_distortion_;
    label_maps_ = std::move(other.label_maps_);
    return *this;
}

void FrameUndistorter::apply(RGBDFrame& frame) const {
    FrameImageBuffers scratch;
    apply(frame, scratch);
}

void FrameUndistorter::apply(RGBDFrame& frame, FrameImageBuffers& scratch) const {
    auto check = [&](Vec2i actual, const Maps& maps, const char* what) {
        if (actual != maps.size)
            throw IoError(frame.depth_path,
                          std::string("cannot undistort the ") + what + " image: it is " + sizeText(actual) +
                              " but the calibrated " + what + " camera is " + sizeText(maps.size),
                          frame.index);
    };
    if (depth_maps_ && !frame.depth_raw.empty()) {
        check(frame.depth_raw.size(), *depth_maps_, "depth");
        scratch.depth_raw.resize(frame.depth_raw.size());
        resampleNearest(depth_maps_->raw_position, frame.depth_raw, scratch.depth_raw, std::uint16_t(0));
        std::swap(frame.depth_raw, scratch.depth_raw);
    }
    if (rgb_maps_ && !frame.rgb.empty()) {
        check(frame.rgb.size(), *rgb_maps_, "rgb");
        scratch.rgb.resize(frame.rgb.size());
        resampleBilinear(rgb_maps_->raw_position, frame.rgb, scratch.rgb);
        std::swap(frame.rgb, scratch.rgb);
    }
    if (label_distortion_.any() && !frame.labels.empty()) {
        // The labels' camera at the label image's resolution: same distortion coefficients (they act
        // on normalised coordinates).
        std::shared_ptr<const Maps> maps;
        {
            const std::lock_guard<std::mutex> lock(label_maps_mutex_);
            if (!label_maps_ || label_maps_->size != frame.labels.size())
                label_maps_ = makeMaps(undistorted_.labelCamera().resized(frame.labels.width(), frame.labels.height()),
                                       label_distortion_);
            maps = label_maps_;
        }
        Image<ClassId> out(frame.labels.size());
        resampleNearest(maps->raw_position, frame.labels, out, kNoLabel);
        frame.labels = std::move(out);
    }
}

}  // namespace voxfuse
