#include "voxfuse/io/FrameFolderSource.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "FrameReading.h"
#include "TextParsing.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/CalibIO.h"
#include "voxfuse/io/ImageIO.h"

namespace voxfuse {

namespace fs = std::filesystem;

namespace {

constexpr double kFramesPerSecond = 30.0;  // the recordings' nominal rate; the files carry no times

}  // namespace

bool FrameFolderSource::parseDepthFileName(const std::string& name, int& number) {
    const std::string prefix = "frame-", suffix = ".depth.png";
    if (name.size() <= prefix.size() + suffix.size() || name.compare(0, prefix.size(), prefix) != 0 ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
        return false;
    const std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
    if (digits.size() > 9 || !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
        return false;
    number = std::stoi(digits);
    return true;
}

FrameFolderSource::FrameFolderSource(const std::string& folder, const std::string& calib_path) : folder_(folder) {
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) throw IoError(folder, "not a folder");
    findFrames();
    loadPoses();
    if (!calib_path.empty())
        calib_ = readCalib(calib_path);
    else
        calibrateFromK();
}

void FrameFolderSource::findFrames() {
    std::error_code ec;
    for (fs::directory_iterator it(folder_, ec), end; !ec && it != end; it.increment(ec)) {
        int number = 0;
        const std::string name = it->path().filename().string();
        if (!parseDepthFileName(name, number)) continue;
        const std::string stem =
            (fs::path(folder_) / name.substr(0, name.size() - std::string(".depth.png").size())).string();
        FrameFiles files{number, stem, it->path().string(), "", false, Mat4f::identity()};
        for (const char* color_suffix : {".color.png", ".color.jpg"})
            if (frame_reading::fileExists(stem + color_suffix)) {
                files.color_path = stem + color_suffix;
                break;
            }
        frames_.push_back(std::move(files));
    }
    if (ec) throw IoError(folder_, "cannot list folder: " + ec.message());
    if (frames_.empty()) throw IoError(folder_, "no frame-XXXXXX.depth.png files");
    std::sort(frames_.begin(), frames_.end(),
              [](const FrameFiles& a, const FrameFiles& b) { return a.number < b.number; });
}

void FrameFolderSource::loadPoses() {
    for (FrameFiles& f : frames_) {
        const std::string pose_path = f.stem + ".pose.txt";
        if (!frame_reading::optionalFilePresent(pose_path)) continue;
        const std::vector<double> m = text::readNumberMatrix(pose_path, 4, 4);
        // Some tools mark lost tracking with -inf in every value of the top three rows: the frame has no
        // pose (counted).
        if (std::none_of(m.begin(), m.begin() + 12, [](double v) { return std::isfinite(v); })) {
            ++lost_poses_;
            continue;
        }
        if (!std::all_of(m.begin(), m.end(), [](double v) { return text::finiteAsFloat(v); }))
            throw IoError(pose_path,
                          "non-finite values in the 4x4 pose (stored as floats); a frame without a pose has -inf in "
                          "all of its top three rows");
        if (std::abs(m[12]) > 1e-6 || std::abs(m[13]) > 1e-6 || std::abs(m[14]) > 1e-6 || std::abs(m[15] - 1.0) > 1e-6)
            throw IoError(pose_path, "the last row of a 4x4 camera-to-world pose must be 0 0 0 1");
        const double R[9] = {m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]};
        std::string problem = text::rotationProblem(R);
        if (!problem.empty())
            problem = "the rotation of the 4x4 camera-to-world pose is " + problem;
        else
            problem = text::positionProblem(m[3], m[7], m[11]);
        if (!problem.empty()) throw IoError(pose_path, problem);
        for (int i = 0; i < 16; ++i) f.T_world_camera.m[i] = float(m[std::size_t(i)]);
        f.has_pose = true;
        ground_truth_.push_back(TimedPose{f.number / kFramesPerSecond, f.T_world_camera});
    }
}

void FrameFolderSource::calibrateFromK() {
    std::string k_path;
    for (const char* name : {"intrinsics.K.txt", "camera-intrinsics.txt"}) {
        const std::string candidate = (fs::path(folder_) / name).string();
        if (frame_reading::optionalFilePresent(candidate)) {
            k_path = candidate;
            break;
        }
    }
    if (k_path.empty())
        throw IoError(folder_, "no intrinsics.K.txt or camera-intrinsics.txt (and no calibration file given)");
    const std::vector<double> K = text::readNumberMatrix(k_path, 3, 3);
    if (!std::all_of(K.begin(), K.end(), [](double v) { return text::finiteAsFloat(v); }))
        throw IoError(k_path, "non-finite value in K (stored as floats)");
    if (!(float(K[0]) > 0.f) || !(float(K[4]) > 0.f))
        throw IoError(k_path, "focal lengths K(0,0) and K(1,1) must be positive");
    if (K[1] != 0.0 || K[3] != 0.0 || K[6] != 0.0 || K[7] != 0.0 || K[8] != 1.0)
        throw IoError(k_path, "expected K = [fx 0 cx; 0 fy cy; 0 0 1] (no skew)");

    // The files do not say the image size; the first depth image does.
    const Image<std::uint16_t> first_depth = readDepthPNG(frames_.front().depth_path);
    Intrinsics depth{first_depth.width(), first_depth.height(), float(K[0]), float(K[4]), float(K[2]), float(K[5])};
    const std::string focal_problem = focalLengthProblem(depth);
    if (!focal_problem.empty()) throw IoError(k_path, focal_problem + " (" + frames_.front().depth_path + ")");
    if (!(depth.cx >= -0.5f && depth.cx <= float(depth.width) - 0.5f && depth.cy >= -0.5f &&
          depth.cy <= float(depth.height) - 0.5f))
        throw IoError(k_path, "the principal point (" + text::formatFloat(depth.cx) + ", " +
                                  text::formatFloat(depth.cy) + ") lies outside the " + std::to_string(depth.width) +
                                  "x" + std::to_string(depth.height) + " depth images (" + frames_.front().depth_path +
                                  ")");
    Intrinsics rgb = depth;
    if (!frames_.front().color_path.empty()) {
        const Vec2i color_size = readColorImage(frames_.front().color_path).size();
        if (color_size != depth.size()) {
            // Same field of view at another resolution; keeps pixel centres consistent (see Intrinsics::downsampled).
            const float sx = float(color_size.x) / float(depth.width), sy = float(color_size.y) / float(depth.height);
            rgb = Intrinsics{color_size.x,
                             color_size.y,
                             depth.fx * sx,
                             depth.fy * sy,
                             (depth.cx + 0.5f) * sx - 0.5f,
                             (depth.cy + 0.5f) * sy - 0.5f};
        }
    }
    calib_.rgb = rgb;
    calib_.depth = depth;
    calib_.T_depth_rgb = Mat4f::identity();
    calib_.disparity = DisparityCalib::affine(0.001f, 0.f);  // millimetres
}

bool FrameFolderSource::next(RGBDFrame& frame) {
    if (position_ >= frames_.size()) return false;
    const int index = int(position_);
    const FrameFiles& f = frames_[position_++];  // moves on even if this frame throws
    const frame_reading::SamplesOutOfRange out_of_range = frame_reading::readDepthAndColor(
        f.depth_path, f.color_path, index, calib_.depth, calib_.rgb, read_.depth_raw, read_.rgb);
    read_.handOver(frame, !f.color_path.empty());
    frame.depth_samples_out_of_range = out_of_range.depth;
    frame.color_samples_out_of_range = out_of_range.color;
    frame.index = index;
    frame.file_number = f.number;
    frame.timestamp_s = f.number / kFramesPerSecond;
    frame.depth_path = f.depth_path;
    frame.has_ground_truth = f.has_pose;
    frame.T_world_camera_gt = f.T_world_camera;
    return true;
}

std::string FrameFolderSource::description() const {
    return "frame folder " + folder_ + " (" + std::to_string(frames_.size()) + " frames, numbers " +
           std::to_string(frames_.front().number) + ".." + std::to_string(frames_.back().number) + ", " +
           std::to_string(ground_truth_.size()) + " with poses" +
           (lost_poses_ > 0 ? ", " + std::to_string(lost_poses_) + " whose pose files mark lost tracking (-inf)"
                            : std::string()) +
           ")";
}

}  // namespace voxfuse
