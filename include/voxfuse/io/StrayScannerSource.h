#pragma once
// An iPhone/iPad LiDAR capture exported by the Stray Scanner app:
//   depth/000000.png ...      16-bit depth in millimetres, 256x192, registered to the colour camera
//   confidence/000000.png ... 8-bit LiDAR confidence per depth pixel: 0 low, 1 medium, 2 high (optional)
//   rgb.mp4                   the colour video (H.264 or HEVC, e.g. 1920x1440), frame i <-> depth i
//   camera_matrix.csv         3x3 K of the colour camera at the video's full resolution
//   odometry.csv              ARKit camera-to-world pose per frame (timestamp, frame, x, y, z, qx, qy, qz, qw)
// imu.csv is not used.

#include <memory>
#include <string>
#include <vector>

#include "voxfuse/io/ImageSource.h"

namespace voxfuse {

class VideoFrameReader;

class StrayScannerSource : public ImageSource {
public:
    // Frames are the depth maps sorted by number; depth frame N pairs with video frame N.
    // Calibration: options.calib_path if given (its colour camera size is then the size colour frames
    // are delivered at), else K from camera_matrix.csv for the colour camera, scaled to the colour
    // size delivered (options.max_color_width) and to the depth maps' size for the depth camera
    // (ARKit registers depth to colour: identity extrinsics), depth in millimetres.
    // Depth samples with confidence below options.min_depth_confidence become 0.
    // Ground truth: the odometry poses, converted to our camera axes (ArkitPose.h); frame timestamps
    // are the odometry's, else frame number / the video's frame rate.
    //
    // Throws IoError for a missing depth/ folder, camera_matrix.csv or rgb.mp4, an undecodable video,
    // depth and video of different aspect ratios; ParseError for malformed CSV lines.
    explicit StrayScannerSource(const std::string& folder, const SourceOptions& options = {});
    ~StrayScannerSource() override;

    const RGBDCalib& calib() const override { return calib_; }
    // Missing or unreadable depth/confidence files, and frames past the end of the video, throw
    // IoError naming file and frame; the next call moves on.
    bool next(RGBDFrame& frame) override;
    int frameCount() const override { return int(frames_.size()); }
    std::string description() const override;
    const std::vector<TimedPose>& groundTruth() const override { return ground_truth_; }

    // True for a folder holding odometry.csv and depth/ (how openImageSource recognises a capture).
    static bool isCapture(const std::string& folder);

private:
    struct FrameFiles {
        int number;
        std::string depth_path;
        std::string confidence_path;  // empty when the capture has no confidence maps
        double timestamp_s = 0.0;
        bool has_pose = false;
        Mat4f T_world_camera = Mat4f::identity();
    };

    void findFrames();
    void calibrate(const std::string& calib_path, int max_color_width);
    void loadPoses();
    void dropLowConfidence(Image<std::uint16_t>& depth, const FrameFiles& files, int index) const;

    std::string folder_;
    std::string video_path_;
    int min_confidence_;
    RGBDCalib calib_;
    std::string calib_origin_;  // for description()
    std::unique_ptr<VideoFrameReader> video_;
    std::vector<FrameFiles> frames_;
    std::vector<TimedPose> ground_truth_;
    FrameImageBuffers read_;  // the next frame is decoded into these
    std::size_t position_ = 0;
};

}  // namespace voxfuse
