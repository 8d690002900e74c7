#pragma once
// A frame's images as the engines read them (View): depth in metres, colour and classes copied and
// checked against the calibration. The main engine makes one per frame, where the map lives.

#include "voxfuse/engines/LowLevelEngine.h"
#include "voxfuse/engines/MainEngine.h"

namespace voxfuse {

struct ViewInputs {
    bool far_depth = false;  // the tracker reads the depths beyond the view frustum too (Tracker::inputs())
    bool labels = false;     // the voxel type holds classes: the frame's label image is used
    bool gpu = false;        // the view lives on the GPU: colour and classes go up once, for every engine
};

// Depth is converted where the map lives (LowLevelEngine), within the view frustum and with
// MainEngineSettings::depth_gap_tolerance; the far depths beyond the frustum into view.far_depth. A
// depth or label image of another size than the calibration's is an IoError naming the frame.
void viewFromFrame(const RGBDFrame& frame, const MainEngineSettings& settings, const ViewInputs& inputs,
                   LowLevelEngine& low_level, View& view);

}  // namespace voxfuse
