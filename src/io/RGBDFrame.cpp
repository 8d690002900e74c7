#include "voxfuse/io/RGBDFrame.h"

#include <cmath>

#include "voxfuse/core/Error.h"

namespace voxfuse {

void checkLabelImageSize(Vec2i label_size, const RGBDCalib& calib, const std::string& path, int frame_index) {
    const Intrinsics& camera = calib.labelCamera();
    if (camera.width <= 0 || camera.height <= 0) return;  // nothing to compare with
    const double label_aspect = label_size.y > 0 ? double(label_size.x) / double(label_size.y) : 0.0;
    const double camera_aspect = double(camera.width) / double(camera.height);
    if (std::abs(label_aspect / camera_aspect - 1.0) <= 0.01) return;
    throw IoError(path,
                  "label image is " + std::to_string(label_size.x) + "x" + std::to_string(label_size.y) +
                      ", not the aspect ratio of the " + (calib.labelsFromColor() ? "colour" : "depth") + " camera (" +
                      std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                      "); any resolution of that aspect ratio (within 1%) is accepted",
                  frame_index);
}

}  // namespace voxfuse
