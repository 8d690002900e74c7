#pragma once
// Synthetic scenes (apps/synth) as an ImageSource rendered in memory, frame by frame, with the Kinect
// depth model and exact ground truth, with no image files and no codec. For benchmarks and checks on
// machines that have only the core library:
//   synthetic[:N]            the bundled data set's room and camera path (default 100 frames);
//   synthetic-corridor[:N]   a walk down a 20 m corridor and back (default 1200 frames): a map that
//                            outgrows an active voxel array, for swapping.

#include <memory>
#include <string>
#include <vector>

#include "voxfuse/io/ImageSource.h"

namespace voxfuse::app {

class SyntheticSource final : public ImageSource {
public:
    enum class Kind { Room, Corridor };
    // `frames` frames (30 fps) at the given resolution; depth with the Kinect noise model of `seed`.
    explicit SyntheticSource(Kind kind, int frames, int width = 640, int height = 480, unsigned seed = 1);
    ~SyntheticSource() override;

    // "synthetic[:N]" or "synthetic-corridor[:N]"; anything else is not a synthetic source.
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
    Kind kind_;
    int frames_;
    int next_ = 0;
    std::vector<TimedPose> ground_truth_;
};

}  // namespace voxfuse::app
