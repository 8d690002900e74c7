#pragma once
// Removes lens distortion from raw frames with per-pixel lookup maps computed once from the
// calibration (the Brown-Conrady model, as OpenCV's initUndistortRectifyMap computes it), so that
// each frame costs one resampling per image.

#include <memory>
#include <mutex>

#include "voxfuse/io/RGBDFrame.h"
#include "voxfuse/objects/RGBDCalib.h"

namespace voxfuse {

class FrameUndistorter {
public:
    // Builds maps for each camera whose LensDistortion is non-zero. An undistorted image keeps its
    // camera's size and intrinsics; only the distortion is gone.
    explicit FrameUndistorter(const RGBDCalib& calib);
    ~FrameUndistorter();
    FrameUndistorter(FrameUndistorter&&) noexcept;
    FrameUndistorter& operator=(FrameUndistorter&&) noexcept;

    // False when neither camera has distortion: apply() leaves frames as they are.
    bool active() const { return rgb_maps_ != nullptr || depth_maps_ != nullptr; }
    // The calibration that undistorted frames have: the input's, with zero distortion.
    const RGBDCalib& undistortedCalib() const { return undistorted_; }

    // Depth is resampled nearest-neighbour (never blended across object edges, and 0 stays "no
    // measurement"), colour bilinearly; pixels that see outside the raw image become 0. Label images
    // (any resolution of the camera that saw them: the colour camera, or the depth camera in a
    // calibration without colour) are resampled nearest-neighbour with that camera's distortion;
    // outside pixels become kNoLabel. An image that does not have its camera's calibrated
    // size throws IoError naming frame.depth_path and frame.index. Safe to call from several threads
    // at once.
    void apply(RGBDFrame& frame) const;
    // The same, remapping depth and colour into `scratch`'s images and swapping them with the frame's:
    // the frame's old images become the scratch of the next call, so a sequence at one size allocates
    // no image memory per frame. One scratch per thread.
    void apply(RGBDFrame& frame, FrameImageBuffers& scratch) const;

private:
    struct Maps;
    // Null when the camera has no distortion (nothing to do for its images).
    static std::unique_ptr<Maps> makeMaps(const Intrinsics& camera, const LensDistortion& distortion);

    std::unique_ptr<Maps> rgb_maps_;
    std::unique_ptr<Maps> depth_maps_;
    RGBDCalib undistorted_;
    LensDistortion label_distortion_;  // the input's calib.labelDistortion() (undistorted_ has none)
    // Label images: maps for the last label resolution seen, made on first use.
    mutable std::mutex label_maps_mutex_;
    mutable std::shared_ptr<const Maps> label_maps_;
};

}  // namespace voxfuse
