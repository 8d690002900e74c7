#pragma once
// A depth-only recording packed for machines that have only the core library and no image codecs,
// such as the lent GPU machine (scripts/gpu_bundle.sh carries a short teddy subset this way). A
// folder holding
//   calib.txt        the calibration, InfiniTAM's format (io/CalibIO.h)
//   depth.bin.gz     gzip of: "VFDEPTH1", uint32 width, height and frame count, then for each frame a
//                    float64 timestamp (s) and width * height uint16 raw depth samples, row by row;
//                    every number little-endian
//   groundtruth.txt  optional: the ground truth, TUM's format (camera-to-world)
// scripts/make_depth_pack.py writes one from a TUM folder.

#include <memory>
#include <string>
#include <vector>

#include "voxfuse/io/ImageSource.h"
#include "voxfuse/io/TrajectoryIO.h"

namespace voxfuse::app {

class DepthPackSource final : public ImageSource {
public:
    // Throws IoError (file and reason) when the folder is not a readable pack.
    explicit DepthPackSource(const std::string& folder);
    ~DepthPackSource() override;

    static bool isDepthPack(const std::string& path);

    const RGBDCalib& calib() const override { return calib_; }
    bool next(RGBDFrame& frame) override;
    int frameCount() const override { return frames_; }
    std::string description() const override;
    const std::vector<TimedPose>& groundTruth() const override { return ground_truth_; }

private:
    void readExactly(void* dst, std::size_t bytes, int frame);

    std::string folder_, depth_path_;
    RGBDCalib calib_;
    std::vector<TimedPose> ground_truth_;
    struct Stream;
    std::unique_ptr<Stream> stream_;
    int width_ = 0, height_ = 0, frames_ = 0, next_ = 0;
};

}  // namespace voxfuse::app
