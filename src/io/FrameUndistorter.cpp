// Lens undistortion of raw frames through OpenCV remap tables, computed once per camera.

#include "voxfuse/io/FrameUndistorter.h"

#include <string>
#include <utility>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "voxfuse/core/Error.h"

namespace voxfuse {

struct FrameUndistorter::Maps {
    Vec2i size{0, 0};
    cv::Mat map1, map2;
};

namespace {

template <typename T>
cv::Mat wrap(Image<T>& image, int type) {
    return cv::Mat(image.height(), image.width(), type, static_cast<void*>(image.host()));
}

std::string sizeText(Vec2i size) { return std::to_string(size.x) + "x" + std::to_string(size.y); }

}  // namespace

std::unique_ptr<FrameUndistorter::Maps> FrameUndistorter::makeMaps(const Intrinsics& k, const LensDistortion& d,
                                                                   int map_type) {
    if (!d.any()) return nullptr;
    if (!k.valid()) throw ConfigError("FrameUndistorter: a camera with lens distortion has invalid intrinsics");
    const cv::Matx33d K(k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0);
    const cv::Vec<double, 5> coefficients(d.k1, d.k2, d.p1, d.p2, d.k3);
    auto maps = std::make_unique<FrameUndistorter::Maps>();
    maps->size = k.size();
    // Same K in and out: the result is the ideal pinhole image with the calibrated intrinsics.
    cv::initUndistortRectifyMap(K, coefficients, cv::noArray(), K, cv::Size(k.width, k.height), map_type, maps->map1,
                                maps->map2);
    return maps;
}

FrameUndistorter::FrameUndistorter(const RGBDCalib& calib)
    // Colour: fixed-point maps, the fast path of bilinear cv::remap. Depth: float maps, because
    // OpenCV 4.6's nearest-neighbour remap with fixed-point maps ignores the border for pixels that
    // map just outside the image (it repeats the edge instead of giving 0 = no measurement).
    : rgb_maps_(makeMaps(calib.rgb, calib.rgb_distortion, CV_16SC2)),
      depth_maps_(makeMaps(calib.depth, calib.depth_distortion, CV_32FC1)),
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
        cv::Mat dst = wrap(scratch.depth_raw, CV_16UC1);
        cv::remap(wrap(frame.depth_raw, CV_16UC1), dst, depth_maps_->map1, depth_maps_->map2, cv::INTER_NEAREST,
                  cv::BORDER_CONSTANT, cv::Scalar(0));
        std::swap(frame.depth_raw, scratch.depth_raw);
    }
    if (rgb_maps_ && !frame.rgb.empty()) {
        check(frame.rgb.size(), *rgb_maps_, "rgb");
        scratch.rgb.resize(frame.rgb.size());
        cv::Mat dst = wrap(scratch.rgb, CV_8UC4);
        cv::remap(wrap(frame.rgb, CV_8UC4), dst, rgb_maps_->map1, rgb_maps_->map2, cv::INTER_LINEAR,
                  cv::BORDER_CONSTANT, cv::Scalar(0, 0, 0, 0));
        std::swap(frame.rgb, scratch.rgb);
    }
    if (label_distortion_.any() && !frame.labels.empty()) {
        // The labels' camera at the label image's resolution: same distortion coefficients (they act
        // on normalised coordinates), float maps for the nearest-neighbour border reason above.
        std::shared_ptr<const Maps> maps;
        {
            const std::lock_guard<std::mutex> lock(label_maps_mutex_);
            if (!label_maps_ || label_maps_->size != frame.labels.size())
                label_maps_ = makeMaps(undistorted_.labelCamera().resized(frame.labels.width(), frame.labels.height()),
                                       label_distortion_, CV_32FC1);
            maps = label_maps_;
        }
        Image<ClassId> out(frame.labels.size());
        cv::Mat dst = wrap(out, CV_16UC1);
        cv::remap(wrap(frame.labels, CV_16UC1), dst, maps->map1, maps->map2, cv::INTER_NEAREST, cv::BORDER_CONSTANT,
                  cv::Scalar(kNoLabel));
        frame.labels = std::move(out);
    }
}

}  // namespace voxfuse
