#pragma once
// The current frame as the engines see it: depth in metres, colour, and the calibration.

#include <cstdint>

#include "voxfuse/core/Image.h"
#include "voxfuse/objects/RGBDCalib.h"

namespace voxfuse {

struct View {
    RGBDCalib calib;
    Image<float> depth;           // metres; 0 = no measurement (depth camera resolution)
    Image<Vec4u8> rgb;            // RGBA, colour camera resolution (may be empty)
    int frame_index = -1;
    double timestamp_s = 0.0;
};

}  // namespace voxfuse
