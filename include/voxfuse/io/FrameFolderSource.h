#pragma once
// A folder in the per-frame layout of 3DMatch/7-Scenes tools: frame-XXXXXX.depth.png (16-bit
// millimetres), frame-XXXXXX.color.png or .color.jpg, frame-XXXXXX.pose.txt (4x4 camera-to-world),
// and intrinsics.K.txt or camera-intrinsics.txt (3x3 K).

#include <string>
#include <vector>

#include "voxfuse/io/ImageSource.h"

namespace voxfuse {

class FrameFolderSource : public ImageSource {
public:
    // Frames are the depth files sorted by number (numbers need not be contiguous); a frame without
    // a colour file has no colour. Calibration: calib_path if given, else K for both cameras, the size
    // taken from the first depth image, colour and depth registered, depth in millimetres. When the
    // first colour image has another size, the colour intrinsics are scaled to it. Timestamps are
    // frame number / 30. A pose file whose top three rows are all non-finite (how some tools mark lost tracking)
    // gives that frame no ground truth, counted in the description; a pose file with some non-finite
    // values, or whose rotation is not one, is an IoError naming it.
    //
    // Throws IoError when the folder has no frames or no intrinsics, ParseError for a malformed K or
    // pose file, IoError for an unreadable first depth or colour image.
    explicit FrameFolderSource(const std::string& folder, const std::string& calib_path = "");

    const RGBDCalib& calib() const override { return calib_; }
    bool next(RGBDFrame& frame) override;
    int frameCount() const override { return int(frames_.size()); }
    std::string description() const override;
    const std::vector<TimedPose>& groundTruth() const override { return ground_truth_; }

    // True for "frame-<digits>.depth.png"; sets `number`.
    static bool parseDepthFileName(const std::string& name, int& number);

private:
    struct FrameFiles {
        int number;
        std::string stem;  // folder/frame-XXXXXX, as spelled on disk
        std::string depth_path;
        std::string color_path;  // empty when there is none
        bool has_pose = false;
        Mat4f T_world_camera = Mat4f::identity();
    };

    void findFrames();
    void loadPoses();
    void calibrateFromK();

    std::string folder_;
    RGBDCalib calib_;
    std::vector<FrameFiles> frames_;
    std::vector<TimedPose> ground_truth_;
    FrameImageBuffers read_;  // the next frame is decoded into these
    std::size_t position_ = 0;
    int lost_poses_ = 0;  // pose files that mark lost tracking
};

}  // namespace voxfuse
