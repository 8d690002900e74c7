#include "voxfuse/io/StrayScannerSource.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <map>

#include "FrameReading.h"
#include "ImageCodecs.h"
#include "ImageHeader.h"
#include "StrayScannerFiles.h"
#include "VideoFrameReader.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/ArkitPose.h"
#include "voxfuse/io/CalibIO.h"
#include "voxfuse/io/ImageIO.h"

namespace voxfuse {

namespace fs = std::filesystem;

namespace {

constexpr double kDefaultFramesPerSecond = 60.0;  // Stray Scanner records at 60 Hz

std::string sizeText(Vec2i size) { return std::to_string(size.x) + "x" + std::to_string(size.y); }

// "000123.png" -> 123.
bool parseFrameFileName(const std::string& name, int& number) {
    const std::string suffix = ".png";
    if (name.size() <= suffix.size() || name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
        return false;
    const std::string digits = name.substr(0, name.size() - suffix.size());
    if (digits.size() > 9 || !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
        return false;
    number = std::stoi(digits);
    return true;
}

// The same camera at another resolution (same field of view), pixel centres kept consistent.
Intrinsics scaledTo(const Intrinsics& k, Vec2i size) {
    const float sx = float(size.x) / float(k.width), sy = float(size.y) / float(k.height);
    return Intrinsics{size.x, size.y, k.fx * sx, k.fy * sy, (k.cx + 0.5f) * sx - 0.5f, (k.cy + 0.5f) * sy - 0.5f};
}

Image<std::uint8_t> readConfidence(const std::string& path, int frame, Vec2i depth_size) {
    if (!frame_reading::fileExists(path)) throw IoError(path, "missing confidence map", frame);
    // Never more pixels than the depth map it belongs to: a corrupt header must not make the decoder allocate
    // gigabytes.
    const image_header::Header h = image_header::read(path);
    if (h.format != image_header::Format::Png || h.width != depth_size.x || h.height != depth_size.y)
        throw IoError(path, "a confidence map must be a PNG of the depth map's size (" + sizeText(depth_size) + ")",
                      frame);
    codecs::DecodedImage m;
    try {
        codecs::readImageFile(path, m);
    } catch (const IoError& e) {
        throw IoError(path, e.reason(), frame);
    }
    if (m.channels != 1) throw IoError(path, "a confidence map must be a single-channel 8- or 16-bit image", frame);
    if (m.size != depth_size)
        throw IoError(
            path, "the confidence map is " + sizeText(m.size) + " but the depth map is " + sizeText(depth_size), frame);
    Image<std::uint8_t> confidence(depth_size);
    for (int y = 0; y < m.size.y; ++y)
        for (int x = 0; x < m.size.x; ++x) confidence.at(x, y) = std::uint8_t(std::min(m.sample(x, y, 0), 255u));
    return confidence;
}

}  // namespace

bool StrayScannerSource::isCapture(const std::string& folder) {
    std::error_code ec;
    return fs::is_regular_file(fs::path(folder) / "odometry.csv", ec) &&
           fs::is_directory(fs::path(folder) / "depth", ec);
}

StrayScannerSource::StrayScannerSource(const std::string& folder, const SourceOptions& options)
    : folder_(folder),
      video_path_((fs::path(folder) / "rgb.mp4").string()),
      min_confidence_(options.min_depth_confidence) {
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) throw IoError(folder, "not a folder");
    if (options.max_color_width < 0)
        throw ConfigError("SourceOptions::max_color_width must be 0 (full size) or positive, got " +
                          std::to_string(options.max_color_width));
    findFrames();
    video_ = std::make_unique<VideoFrameReader>(video_path_);
    calibrate(options.calib_path, options.max_color_width);
    loadPoses();
}

StrayScannerSource::~StrayScannerSource() = default;

void StrayScannerSource::findFrames() {
    const fs::path depth_folder = fs::path(folder_) / "depth";
    const fs::path confidence_folder = fs::path(folder_) / "confidence";
    std::error_code ec;
    const bool has_confidence = fs::is_directory(confidence_folder, ec);
    for (fs::directory_iterator it(depth_folder, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string name = it->path().filename().string();
        int number = 0;
        if (!parseFrameFileName(name, number)) continue;
        frames_.push_back(FrameFiles{number, it->path().string(),
                                     has_confidence ? (confidence_folder / name).string() : std::string(), 0.0, false,
                                     Mat4f::identity()});
    }
    if (ec) throw IoError(depth_folder.string(), "cannot list the depth folder: " + ec.message());
    if (frames_.empty())
        throw IoError(depth_folder.string(), "no depth maps (NNNNNN.png) in the capture's depth folder");
    std::sort(frames_.begin(), frames_.end(),
              [](const FrameFiles& a, const FrameFiles& b) { return a.number < b.number; });
}

void StrayScannerSource::calibrate(const std::string& calib_path, int max_color_width) {
    const Vec2i depth_size = readDepthPNG(frames_.front().depth_path).size();
    if (!calib_path.empty()) {
        calib_ = readCalib(calib_path);
        if (calib_.depth.size() != depth_size)
            throw IoError(calib_path, "the depth camera is " + sizeText(calib_.depth.size()) +
                                          " but the capture's depth maps are " + sizeText(depth_size));
        calib_origin_ = calib_path;
        return;
    }
    const std::string k_path = (fs::path(folder_) / "camera_matrix.csv").string();
    const stray_scanner::CameraMatrix K = stray_scanner::readCameraMatrix(k_path);
    const Vec2i video_size = video_->size();
    const Intrinsics full{video_size.x, video_size.y, float(K.fx), float(K.fy), float(K.cx), float(K.cy)};
    const std::string focal_problem = focalLengthProblem(full);
    if (!focal_problem.empty()) throw IoError(k_path, focal_problem + " (the video's frames)");
    if (K.cx <= 0.0 || K.cx >= video_size.x || K.cy <= 0.0 || K.cy >= video_size.y)
        throw IoError(k_path, "the principal point (" + std::to_string(K.cx) + ", " + std::to_string(K.cy) +
                                  ") lies outside the " + sizeText(video_size) +
                                  " video frames: camera_matrix.csv and rgb.mp4 do not belong together");
    // Depth is registered to colour: both images must show the same field of view.
    const double aspect_mismatch = std::abs(double(video_size.x) * depth_size.y - double(video_size.y) * depth_size.x) /
                                   (double(video_size.y) * depth_size.x);
    if (aspect_mismatch > 0.01)
        throw IoError(folder_, "the depth maps are " + sizeText(depth_size) + " but the video frames are " +
                                   sizeText(video_size) +
                                   ": different aspect ratios (was the video rotated or cropped?)");
    Vec2i color_size = video_size;
    if (max_color_width > 0 && video_size.x > max_color_width)
        color_size = Vec2i{max_color_width, int(std::lround(double(video_size.y) * max_color_width / video_size.x))};
    calib_.rgb = scaledTo(full, color_size);
    calib_.depth = scaledTo(full, depth_size);
    calib_.T_depth_rgb = Mat4f::identity();
    calib_.disparity = DisparityCalib::affine(0.001f, 0.f);  // millimetres
    calib_origin_ = "camera_matrix.csv";
}

void StrayScannerSource::loadPoses() {
    const std::string path = (fs::path(folder_) / "odometry.csv").string();
    std::map<int, stray_scanner::OdometryRow> by_frame;
    for (const stray_scanner::OdometryRow& row : stray_scanner::readOdometry(path)) by_frame[row.frame] = row;
    const double fps = video_->framesPerSecond() > 0.0 ? video_->framesPerSecond() : kDefaultFramesPerSecond;
    for (FrameFiles& f : frames_) {
        const auto it = by_frame.find(f.number);
        if (it == by_frame.end()) {
            // No row: the time follows from the nearest row's at the video's rate, on the same clock as
            // its neighbours (number / fps alone would put it thousands of seconds from them).
            f.timestamp_s = f.number / fps;
            if (!by_frame.empty()) {
                auto nearest = by_frame.lower_bound(f.number);  // the first row after the frame
                if (nearest == by_frame.end() ||
                    (nearest != by_frame.begin() && f.number - std::prev(nearest)->first < nearest->first - f.number))
                    nearest = std::prev(nearest);
                f.timestamp_s = nearest->second.timestamp_s + (f.number - nearest->first) / fps;
            }
            continue;
        }
        f.timestamp_s = it->second.timestamp_s;
        f.T_world_camera = poseFromArkit(it->second.position, it->second.quaternion_xyzw);
        f.has_pose = true;
        ground_truth_.push_back(TimedPose{f.timestamp_s, f.T_world_camera});
    }
}

void StrayScannerSource::dropLowConfidence(Image<std::uint16_t>& depth, const FrameFiles& files, int index) const {
    if (min_confidence_ <= 0 || files.confidence_path.empty()) return;
    const Image<std::uint8_t> confidence = readConfidence(files.confidence_path, index, depth.size());
    for (std::size_t i = 0; i < depth.pixelCount(); ++i)
        if (confidence.host()[i] < min_confidence_) depth.host()[i] = 0;
}

bool StrayScannerSource::next(RGBDFrame& frame) {
    if (position_ >= frames_.size()) return false;
    const int index = int(position_);
    const FrameFiles& f = frames_[position_++];  // moves on even if this frame throws
    const std::size_t out_of_range = frame_reading::readDepth(f.depth_path, index, calib_.depth, read_.depth_raw);
    dropLowConfidence(read_.depth_raw, f, index);
    if (!video_->read(f.number, read_.rgb, calib_.rgb.size()))
        throw IoError(video_path_,
                      "the video ends before frame " + std::to_string(f.number) + " (depth map " + f.depth_path + ")",
                      index);
    read_.handOver(frame, true);
    frame.depth_samples_out_of_range = out_of_range;
    frame.index = index;
    frame.file_number = f.number;
    frame.timestamp_s = f.timestamp_s;
    frame.depth_path = f.depth_path;
    frame.has_ground_truth = f.has_pose;
    frame.T_world_camera_gt = f.T_world_camera;
    return true;
}

std::string StrayScannerSource::description() const {
    return "Stray Scanner capture " + folder_ + " (" + std::to_string(frames_.size()) + " frames, depth " +
           sizeText(calib_.depth.size()) + ", colour " + sizeText(video_->size()) + " video" +
           (video_->frameCount() >= 0 ? " of " + std::to_string(video_->frameCount()) + " frames" : std::string()) +
           " delivered at " + sizeText(calib_.rgb.size()) + ", " + std::to_string(ground_truth_.size()) +
           " ARKit poses, calibration from " + calib_origin_ +
           (frames_.front().confidence_path.empty() ? std::string(", no confidence maps")
                                                    : ", depth confidence >= " + std::to_string(min_confidence_)) +
           ")";
}

}  // namespace voxfuse
