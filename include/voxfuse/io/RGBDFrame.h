#pragma once
// One frame as read from a source, before any processing: raw 16-bit depth (converted to metres by
// the low-level engine using the calibration's DisparityCalib) and colour.

#include <cstdint>
#include <string>
#include <utility>

#include "voxfuse/core/Image.h"
#include "voxfuse/objects/ClassLabel.h"
#include "voxfuse/objects/RGBDCalib.h"

namespace voxfuse {

struct RGBDFrame {
    int index = -1;                  // 0-based position in the source
    long long file_number = -1;      // the number in the frame's file names where the source names them
                                     // so (frame folders, Stray Scanner captures: frame-000015 -> 15;
                                     // numbers may skip), -1 otherwise
    double timestamp_s = 0.0;        // source timestamp (frame index / 30 when the source has none)
    double rgb_timestamp_s = -1.0;   // the colour image's own time where the source pairs images taken
                                     // apart (TUM: timestamp_s is the depth image's); < 0 otherwise
    Image<std::uint16_t> depth_raw;  // raw depth samples; 0 = no measurement
    // Samples above the maximum the depth file declares (a PGM's maxval): invalid, so read as 0.
    std::size_t depth_samples_out_of_range = 0;
    Image<Vec4u8> rgb;  // RGBA; empty when the source has no colour
    // Colour samples above the maximum the colour file declares (a PPM's maxval): read as full intensity.
    std::size_t color_samples_out_of_range = 0;
    bool has_ground_truth = false;
    Mat4f T_world_camera_gt = Mat4f::identity();  // ground-truth pose when has_ground_truth
    std::string depth_path;                       // where the depth came from, for error messages
    // Semantic labels (io/LabelledImageSource.h): one class id per pixel, kNoLabel where there is none,
    // seen by the colour camera (any resolution of the colour image's aspect ratio); empty when the
    // frame has none.
    Image<ClassId> labels;
    std::string labels_path;
};

// The images a source decodes the next frame into before it hands them over by swapping them with the
// frame's: a frame that fails to read leaves the caller's frame as it was, and the frame's previous
// images come back to be decoded into, so reading a sequence allocates no image memory per frame.
struct FrameImageBuffers {
    Image<std::uint16_t> depth_raw;
    Image<Vec4u8> rgb;

    void handOver(RGBDFrame& frame, bool with_rgb) {
        std::swap(depth_raw, frame.depth_raw);
        if (with_rgb)
            std::swap(rgb, frame.rgb);
        else
            frame.rgb = Image<Vec4u8>();
    }
};

// A label image may have any resolution, but must show calib.labelCamera()'s field of view: its aspect
// ratio within 1% (another one would be a crop, which the engine cannot place). Throws IoError naming
// `path`, `frame_index` and both sizes otherwise.
void checkLabelImageSize(Vec2i label_size, const RGBDCalib& calib, const std::string& path, int frame_index);

}  // namespace voxfuse
