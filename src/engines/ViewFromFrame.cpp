#include "ViewFromFrame.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace {

// Frame images that go to the GPU every frame live in pinned host memory.
template <class T>
void copyImage(const Image<T>& from, bool used, bool gpu, Image<T>& to) {
    if (!used || from.empty()) {
        to = Image<T>();
        return;
    }
    to.resize(from.size(), true, false, gpu ? HostMemory::Pinned : HostMemory::Pageable);
    std::memcpy(static_cast<void*>(to.host()), from.host(), from.pixelCount() * sizeof(T));
}

}  // namespace

void viewFromFrame(const RGBDFrame& frame, const MainEngineSettings& settings, const ViewInputs& inputs,
                   LowLevelEngine& low_level, View& view) {
    constexpr float kInfinity = std::numeric_limits<float>::infinity();
    const float near_m = settings.scene.view_frustum_min_m, far_m = settings.scene.view_frustum_max_m;
    low_level.convertDepthToMetres(frame.depth_raw, view.calib.disparity, view.calib.depth.fx, near_m, far_m,
                                   settings.depth_gap_tolerance, view.depth);
    if (inputs.far_depth)
        low_level.convertDepthToMetres(frame.depth_raw, view.calib.disparity, view.calib.depth.fx,
                                       std::nextafter(far_m, kInfinity), kInfinity, 0.f, view.far_depth);
    copyImage(frame.rgb, true, inputs.gpu, view.rgb);
    copyImage(frame.labels, inputs.labels, inputs.gpu, view.labels);  // only the semantic voxel types use them
    view.frame_index = frame.index;
    view.timestamp_s = frame.timestamp_s;
    if (view.depth.size() != view.calib.depth.size())
        throw IoError(frame.depth_path,
                      "depth image is " + std::to_string(view.depth.width()) + "x" +
                          std::to_string(view.depth.height()) + " but the calibration says " +
                          std::to_string(view.calib.depth.width) + "x" + std::to_string(view.calib.depth.height),
                      frame.index);
    if (!view.labels.empty()) checkLabelImageSize(view.labels.size(), view.calib, frame.labels_path, frame.index);
    if (inputs.gpu) {
        // The depth was made there; the colour serves colour voxels and the colour trackers.
        if (!view.rgb.empty()) view.rgb.memory().updateDevice();
        if (!view.labels.empty()) view.labels.memory().updateDevice();
    }
}

}  // namespace voxfuse
