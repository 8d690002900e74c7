#pragma once
// A folder in the TUM RGB-D benchmark layout: rgb.txt and depth.txt ("timestamp filename" lines,
// file names relative to the folder), the PNGs they list, and optionally groundtruth.txt.

#include <string>
#include <vector>

#include "voxfuse/io/ImageSource.h"

namespace voxfuse {

class TumSource : public ImageSource {
public:
    static constexpr double kMaxTimeDifference_s = 0.02;  // as TUM's associate.py and evaluation tools

    // Pairs depth and rgb images by timestamp: candidate pairs closer than kMaxTimeDifference_s are
    // taken greedily, closest first, each rgb image at most once (TUM's associate.py rule); frames
    // keep depth.txt's order and a depth image without a partner is dropped and counted. Listed
    // images missing on disk are counted; those before the first or after the last image on disk are
    // left out (the benchmark's lists often cover more than a trimmed copy holds), those between take
    // part, and their frames throw IoError naming them when read. Each frame's timestamp is its depth timestamp; it has
    // ground truth when groundtruth.txt has a pose within kMaxTimeDifference_s (interpolated between samples).
    //
    // Calibration: calib_path if given, else calib.txt in the folder, else TUM fr1/fr2/fr3 guessed
    // from a "freiburgN" or "frN" in the folder name, else Kinect v1 defaults with the TUM depth
    // scale (value / 5000) and a warning on stderr.
    //
    // Throws IoError/ParseError for a missing or malformed list, trajectory or calibration file.
    explicit TumSource(const std::string& folder, const std::string& calib_path = "");

    const RGBDCalib& calib() const override { return calib_; }
    bool next(RGBDFrame& frame) override;
    int frameCount() const override { return int(pairs_.size()); }
    std::string description() const override;
    const std::vector<TimedPose>& groundTruth() const override { return ground_truth_; }

    int droppedDepthFrames() const { return dropped_depth_frames_; }  // no rgb partner in time
    int missingListedFiles() const { return missing_listed_files_; }  // listed, but not on disk

private:
    struct FramePair {
        double depth_time_s, rgb_time_s;
        std::string depth_path;
        std::string rgb_path;
    };

    void chooseCalibration(const std::string& calib_path);
    void associate(const std::string& rgb_list, const std::string& depth_list);

    std::string folder_;
    RGBDCalib calib_;
    std::string calib_origin_;  // for description()
    std::vector<FramePair> pairs_;
    std::vector<TimedPose> ground_truth_;
    FrameImageBuffers read_;  // the next frame is decoded into these
    std::size_t position_ = 0;
    int dropped_depth_frames_ = 0;
    int missing_listed_files_ = 0;
    int missing_between_files_ = 0;  // of those, the ones between images on disk (their frames cannot be read)
};

}  // namespace voxfuse
