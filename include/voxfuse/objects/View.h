#pragma once
// The current frame as the engines see it: depth in metres, colour, and the calibration.

#include <cstdint>

#include "voxfuse/core/Image.h"
#include "voxfuse/objects/ClassLabel.h"
#include "voxfuse/objects/FrameClock.h"
#include "voxfuse/objects/RGBDCalib.h"

namespace voxfuse {

struct View {
    RGBDCalib calib;
    Image<float> depth;      // metres; 0 = no measurement (depth camera resolution)
    Image<Vec4u8> rgb;       // RGBA, colour camera resolution (may be empty)
    Image<float> far_depth;  // metres beyond the map's range (SceneParams::view_frustum_max_m), 0 elsewhere;
                             // only for rgbd's far field (FarFieldKeyframes), else empty
    Image<ClassId> labels;   // class per pixel (kNoLabel: none), colour camera geometry at its own
                             // resolution; empty when the frame has no labels
    int frame_index = -1;
    double timestamp_s = 0.0;

    FrameClock clock() const { return {timestamp_s, frame_index}; }
    // The colour camera as the colour image sees it: an image of another size than calibrated is the
    // same camera at that resolution. Integration, the colour trackers and relocalisation all use it.
    // For a view with a colour image.
    Intrinsics colorCamera() const {
        return rgb.size() == calib.rgb.size() ? calib.rgb : calib.rgb.resized(rgb.width(), rgb.height());
    }
};

}  // namespace voxfuse
