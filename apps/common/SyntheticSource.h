#pragma once
// The synthetic room (apps/synth) as an ImageSource rendered in memory, frame by frame: the bundled
// data set's scene, camera path and Kinect depth model, with no image files and no codec. For
// benchmarks and checks on machines that have only the core library (voxfuse_bench synthetic[:N]).

#include <memory>
#include <string>
#include <vector>

#include "voxfuse/io/ImageSource.h"

namespace voxfuse::app {

class SyntheticSource final : public ImageSource {
public:
    // `frames` frames (30 fps) at the given resolution; depth with the Kinect noise model of `seed`.
    explicit SyntheticSource(int frames, int width = 640, int height = 480, unsigned seed = 1);
    ~SyntheticSource() override;

    // "synthetic" or "synthetic:N" (N frames, default 100); anything else is not a synthetic source.
    static bool isSyntheticName(const std::string& path);
    static std::unique_ptr<SyntheticSource> open(const std::string& path);

    const RGBDCalib& calib() const override { return calib_; }
    bool next(RGBDFrame& frame) override;
    int frameCount() const override { return frames_; }
    std::string description() const override;
    const std::vector<TimedPose>& groundTruth() const override { return ground_truth_; }

private:
    struct Renderer;
    std::unique_ptr<Renderer> renderer_;
    RGBDCalib calib_;
    int frames_;
    int next_ = 0;
    std::vector<TimedPose> ground_truth_;
};

}  // namespace voxfuse::app
