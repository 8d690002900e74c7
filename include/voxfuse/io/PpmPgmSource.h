#pragma once
// An InfiniTAM-style image sequence named by printf patterns, e.g. "rgb/%04i.ppm" and
// "depth/%04i.pgm" (16-bit big-endian PGM depth). PNG files work too, chosen by extension.

#include <string>
#include <vector>

#include "voxfuse/io/ImageSource.h"

namespace voxfuse {

class PpmPgmSource : public ImageSource {
public:
    static constexpr int kMaxGap = 1000;  // missing indices in a row that a sequence may step over

    // Each pattern must hold exactly one integer conversion (%d or %i, with optional flags, width
    // and precision; "%%" is a literal '%'), else ConfigError. An empty rgb_pattern means depth only.
    // The sequence runs from first_index to the last index with a file, across gaps of up to kMaxGap
    // indices: next() reports each missing frame as an IoError naming its file and goes on. No files
    // at first_index is an IoError. Ground truth: a TUM-format "groundtruth.txt" in the
    // folder of the depth files is used when it holds exactly as many poses as there are frames,
    // pose i belonging to frame i (its own timestamps are replaced by the frames'); otherwise it is
    // ignored with a warning on stderr. Frame timestamps are file index / 30.
    PpmPgmSource(std::string rgb_pattern, std::string depth_pattern, const std::string& calib_path,
                 int first_index = 0);

    const RGBDCalib& calib() const override { return calib_; }
    // A present but unreadable file throws IoError naming file and frame; the next call moves on.
    bool next(RGBDFrame& frame) override;
    int frameCount() const override { return frame_count_; }
    std::string description() const override;
    const std::vector<TimedPose>& groundTruth() const override { return ground_truth_; }

private:
    // The file name for `index`; only called with patterns the constructor has validated.
    static std::string fileName(const std::string& pattern, int index);
    void loadGroundTruth();

    std::string rgb_pattern_;
    std::string depth_pattern_;
    int first_index_;
    RGBDCalib calib_;
    int frame_count_ = 0;
    int missing_frames_ = 0;               // indices in the range without their files
    int position_ = 0;                     // 0-based index of the next frame
    std::vector<TimedPose> ground_truth_;  // empty, or one pose per frame
    FrameImageBuffers read_;               // the next frame is decoded into these
};

}  // namespace voxfuse
