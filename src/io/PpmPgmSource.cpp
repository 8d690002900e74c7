#include "voxfuse/io/PpmPgmSource.h"

#include <climits>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "FrameReading.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/CalibIO.h"

namespace voxfuse {

namespace {

bool isDigit(char c) { return c >= '0' && c <= '9'; }

// Accepts exactly one "%[flags][width][.precision](d|i)" plus any number of "%%"; anything else
// would make snprintf read arguments that are not there.
void validatePattern(const std::string& pattern, const char* which) {
    auto fail = [&](const std::string& why) {
        throw ConfigError(std::string(which) + " pattern '" + pattern + "': " + why +
                          " (expected exactly one integer conversion such as %04i or %d)");
    };
    int conversions = 0;
    for (std::size_t i = 0; i < pattern.size(); ++i) {
        if (pattern[i] != '%') continue;
        const std::size_t start = i++;
        if (i < pattern.size() && pattern[i] == '%') continue;
        while (i < pattern.size() && std::string("-+ #0").find(pattern[i]) != std::string::npos) ++i;
        while (i < pattern.size() && isDigit(pattern[i])) ++i;
        if (i < pattern.size() && pattern[i] == '.') {
            ++i;
            while (i < pattern.size() && isDigit(pattern[i])) ++i;
        }
        if (i >= pattern.size() || (pattern[i] != 'd' && pattern[i] != 'i'))
            fail("unsupported conversion '" + pattern.substr(start, i + 1 - start) + "'");
        if (i - start > 8) fail("conversion '" + pattern.substr(start, i + 1 - start) + "' is too long");
        ++conversions;
    }
    if (conversions != 1) fail(conversions == 0 ? "no integer conversion" : "more than one conversion");
}

}  // namespace

std::string PpmPgmSource::fileName(const std::string& pattern, int index) {
    const int length = std::snprintf(nullptr, 0, pattern.c_str(), index);
    if (length < 0) throw ConfigError("cannot format the pattern '" + pattern + "'");
    std::string name(std::size_t(length) + 1, '\0');
    std::snprintf(name.data(), name.size(), pattern.c_str(), index);
    name.resize(std::size_t(length));
    return name;
}

PpmPgmSource::PpmPgmSource(std::string rgb_pattern, std::string depth_pattern, const std::string& calib_path,
                           int first_index)
    : rgb_pattern_(std::move(rgb_pattern)), depth_pattern_(std::move(depth_pattern)), first_index_(first_index) {
    if (depth_pattern_.empty()) throw ConfigError("a PPM/PGM sequence needs a depth pattern");
    validatePattern(depth_pattern_, "depth");
    if (!rgb_pattern_.empty()) validatePattern(rgb_pattern_, "rgb");
    if (first_index_ < 0) throw ConfigError("first index must not be negative, got " + std::to_string(first_index_));
    calib_ = readCalib(calib_path);

    // Counted up front so that frameCount() is known and ground truth can be matched by count. A gap
    // of up to kMaxGap indices does not end the sequence: its frames are reported missing by next().
    auto complete = [&](int index) {
        return frame_reading::fileExists(fileName(depth_pattern_, index)) &&
               (rgb_pattern_.empty() || frame_reading::fileExists(fileName(rgb_pattern_, index)));
    };
    auto anyFile = [&](int index) {
        return frame_reading::fileExists(fileName(depth_pattern_, index)) ||
               (!rgb_pattern_.empty() && frame_reading::fileExists(fileName(rgb_pattern_, index)));
    };
    if (!complete(first_index_)) {
        const std::string depth_file = fileName(depth_pattern_, first_index_);
        const std::string missing =
            frame_reading::fileExists(depth_file) ? fileName(rgb_pattern_, first_index_) : depth_file;
        throw IoError(missing, "no frames: the first file of the sequence does not exist");
    }
    int last = first_index_;
    for (int index = first_index_ + 1; index < INT_MAX && index - last <= kMaxGap; ++index)
        if (anyFile(index)) last = index;
    frame_count_ = last - first_index_ + 1;
    for (int index = first_index_; index <= last; ++index) missing_frames_ += !complete(index);
    loadGroundTruth();
}

void PpmPgmSource::loadGroundTruth() {
    const std::filesystem::path depth_folder =
        std::filesystem::path(fileName(depth_pattern_, first_index_)).parent_path();
    const std::string path = (depth_folder / "groundtruth.txt").string();
    if (!frame_reading::optionalFilePresent(path)) return;
    std::vector<TimedPose> poses = readTumTrajectory(path);
    if (int(poses.size()) != frame_count_) {
        std::cerr << "voxfuse: warning: ignoring " << path << ": it holds " << poses.size() << " poses for "
                  << frame_count_ << " frames (poses are matched to frames by position, so the counts must agree)\n";
        return;
    }
    for (int i = 0; i < frame_count_; ++i) poses[std::size_t(i)].timestamp_s = double(first_index_ + i) / 30.0;
    ground_truth_ = std::move(poses);
}

bool PpmPgmSource::next(RGBDFrame& frame) {
    if (position_ >= frame_count_) return false;
    const int position = position_++;  // moves on even if this frame throws
    const int file_index = first_index_ + position;
    const std::string depth_path = fileName(depth_pattern_, file_index);
    for (const std::string* pattern : {&depth_pattern_, &rgb_pattern_}) {
        if (pattern->empty()) continue;
        const std::string path = fileName(*pattern, file_index);
        if (!frame_reading::fileExists(path))
            throw IoError(path,
                          "missing: a gap in the sequence (index " + std::to_string(file_index) +
                              "); it goes on to index " + std::to_string(first_index_ + frame_count_ - 1),
                          position);
    }
    const frame_reading::SamplesOutOfRange out_of_range = frame_reading::readDepthAndColor(
        depth_path, rgb_pattern_.empty() ? std::string() : fileName(rgb_pattern_, file_index), position, calib_.depth,
        calib_.rgb, read_.depth_raw, read_.rgb);
    read_.handOver(frame, !rgb_pattern_.empty());
    frame.depth_samples_out_of_range = out_of_range.depth;
    frame.color_samples_out_of_range = out_of_range.color;
    frame.index = position;
    frame.timestamp_s = double(file_index) / 30.0;
    frame.depth_path = depth_path;
    frame.has_ground_truth = !ground_truth_.empty();
    frame.T_world_camera_gt =
        frame.has_ground_truth ? ground_truth_[std::size_t(position)].T_world_camera : Mat4f::identity();
    return true;
}

std::string PpmPgmSource::description() const {
    return "PPM/PGM sequence " + depth_pattern_ + (rgb_pattern_.empty() ? "" : " + " + rgb_pattern_) + " (" +
           std::to_string(frame_count_) + " frames from index " + std::to_string(first_index_) +
           (missing_frames_ > 0 ? ", " + std::to_string(missing_frames_) + " of them missing" : std::string()) +
           (ground_truth_.empty() ? "" : ", with ground truth") + ")";
}

}  // namespace voxfuse
