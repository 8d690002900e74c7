#include "voxfuse/io/TumSource.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "FrameReading.h"
#include "TextParsing.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/CalibIO.h"

namespace voxfuse {

namespace fs = std::filesystem;

namespace {

// "fr3" for ".../rgbd_dataset_freiburg3_teddy" or ".../tum_fr3_teddy_200", 0 when the name says nothing.
int freiburgFromName(const fs::path& folder) {
    std::string name = folder.filename().string();
    for (char& c : name) c = char(std::tolower(static_cast<unsigned char>(c)));
    for (int n = 1; n <= 3; ++n) {
        const std::string digit = std::to_string(n);
        for (const std::string& key : {"freiburg" + digit, "fr" + digit}) {
            const std::size_t at = name.find(key);
            // "fr1" must not be the start of "fr10"; the character after the digit must not be one.
            if (at != std::string::npos &&
                (at + key.size() == name.size() || !std::isdigit(static_cast<unsigned char>(name[at + key.size()]))))
                return n;
        }
    }
    return 0;
}

fs::path normalisedFolder(const std::string& folder) {
    std::error_code ec;
    fs::path p = fs::weakly_canonical(fs::path(folder), ec);
    if (ec) p = fs::path(folder).lexically_normal();
    if (p.filename().empty()) p = p.parent_path();  // "a/b/" -> "a/b"
    return p;
}

}  // namespace

TumSource::TumSource(const std::string& folder, const std::string& calib_path) : folder_(folder) {
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) throw IoError(folder, "not a folder");
    chooseCalibration(calib_path);
    associate("rgb.txt", "depth.txt");
    const std::string gt_path = (fs::path(folder) / "groundtruth.txt").string();
    if (frame_reading::optionalFilePresent(gt_path)) ground_truth_ = readTumTrajectory(gt_path);
}

void TumSource::chooseCalibration(const std::string& calib_path) {
    const std::string own_calib = (fs::path(folder_) / "calib.txt").string();
    if (!calib_path.empty()) {
        calib_ = readCalib(calib_path);
        calib_origin_ = calib_path;
    } else if (frame_reading::optionalFilePresent(own_calib)) {
        calib_ = readCalib(own_calib);
        calib_origin_ = own_calib;
    } else if (const int freiburg = freiburgFromName(normalisedFolder(folder_))) {
        calib_ = tumCalib(freiburg);
        calib_origin_ = "TUM fr" + std::to_string(freiburg) + ", guessed from the folder name";
    } else {
        calib_ = kinectV1DefaultCalib();
        calib_.disparity = DisparityCalib::affine(0.0002f, 0.f);  // TUM PNGs store depth * 5000
        calib_origin_ = "Kinect v1 defaults with TUM depth scale (a guess)";
        std::cerr << "voxfuse: warning: " << folder_
                  << ": no calib.txt and no freiburg1/2/3 (fr1/2/3) in the folder name; using Kinect v1 default "
                     "intrinsics with depth = value / 5000. Pass a calibration file for accurate results.\n";
    }
}

void TumSource::associate(const std::string& rgb_list, const std::string& depth_list) {
    const fs::path folder(folder_);
    using frame_reading::ListedImage;
    // Listed images missing on disk (counted in missing_listed_files_): before the first and after the
    // last image on disk they are left out (a trimmed copy keeps the benchmark's full lists); between
    // them they take part as listed, so that a frame that needs one is an unreadable frame at its own
    // place, named when it is read, not left out silently with the frames after it moved up.
    auto listed = [&](const std::string& list) {
        std::vector<ListedImage> images =
            frame_reading::readTimestampedImageList((folder / list).string(), missing_listed_files_);
        const auto on_disk = [](const ListedImage& i) { return i.on_disk; };
        const auto first = std::find_if(images.begin(), images.end(), on_disk);
        if (first == images.end()) return std::vector<ListedImage>();
        const auto last = std::find_if(images.rbegin(), images.rend(), on_disk).base();
        missing_between_files_ += int(std::count_if(first, last, [](const ListedImage& i) { return !i.on_disk; }));
        return std::vector<ListedImage>(first, last);
    };
    std::vector<ListedImage> rgb = listed(rgb_list);
    const std::vector<ListedImage> depth = listed(depth_list);
    std::stable_sort(rgb.begin(), rgb.end(),
                     [](const ListedImage& a, const ListedImage& b) { return a.time_s < b.time_s; });

    struct Candidate {
        double difference_s;
        std::size_t depth, rgb;
    };
    std::vector<Candidate> candidates;
    for (std::size_t d = 0; d < depth.size(); ++d) {
        const double t = depth[d].time_s;
        auto it = std::lower_bound(rgb.begin(), rgb.end(), t - kMaxTimeDifference_s,
                                   [](const ListedImage& image, double time) { return image.time_s < time; });
        for (; it != rgb.end() && it->time_s <= t + kMaxTimeDifference_s; ++it)
            candidates.push_back({std::abs(it->time_s - t), d, std::size_t(it - rgb.begin())});
    }
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const Candidate& a, const Candidate& b) { return a.difference_s < b.difference_s; });

    std::vector<long> rgb_for_depth(depth.size(), -1);
    std::vector<bool> rgb_used(rgb.size(), false);
    for (const Candidate& c : candidates) {
        if (rgb_for_depth[c.depth] >= 0 || rgb_used[c.rgb]) continue;
        rgb_for_depth[c.depth] = long(c.rgb);
        rgb_used[c.rgb] = true;
    }
    for (std::size_t d = 0; d < depth.size(); ++d) {
        if (rgb_for_depth[d] < 0) {
            ++dropped_depth_frames_;
            continue;
        }
        const ListedImage& paired_rgb = rgb[std::size_t(rgb_for_depth[d])];
        pairs_.push_back({depth[d].time_s, paired_rgb.time_s, depth[d].path, paired_rgb.path});
    }
}

bool TumSource::next(RGBDFrame& frame) {
    if (position_ >= pairs_.size()) return false;
    const int index = int(position_);
    const FramePair& pair = pairs_[position_++];  // moves on even if this frame throws
    const frame_reading::SamplesOutOfRange out_of_range = frame_reading::readDepthAndColor(
        pair.depth_path, pair.rgb_path, index, calib_.depth, calib_.rgb, read_.depth_raw, read_.rgb);
    read_.handOver(frame, true);
    frame.depth_samples_out_of_range = out_of_range.depth;
    frame.color_samples_out_of_range = out_of_range.color;
    frame.index = index;
    frame.timestamp_s = pair.depth_time_s;
    frame.rgb_timestamp_s = pair.rgb_time_s;
    frame.depth_path = pair.depth_path;
    frame.T_world_camera_gt = Mat4f::identity();
    frame.has_ground_truth =
        interpolatePose(ground_truth_, pair.depth_time_s, kMaxTimeDifference_s, frame.T_world_camera_gt);
    return true;
}

std::string TumSource::description() const {
    std::string d = "TUM folder " + folder_ + " (" + std::to_string(pairs_.size()) + " frames";
    if (dropped_depth_frames_ > 0)
        d += "; " + std::to_string(dropped_depth_frames_) + " depth frames without an rgb image within 0.02 s dropped";
    if (missing_listed_files_ > missing_between_files_)
        d += "; " + std::to_string(missing_listed_files_ - missing_between_files_) +
             " listed images beyond those on disk left out";
    if (missing_between_files_ > 0)
        d += "; " + std::to_string(missing_between_files_) +
             " listed images missing between those on disk (their frames are unreadable)";
    d += "; calibration: " + calib_origin_;
    d += ground_truth_.empty() ? "; no ground truth)"
                               : "; ground truth: " + std::to_string(ground_truth_.size()) + " poses)";
    return d;
}

}  // namespace voxfuse
