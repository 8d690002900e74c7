#pragma once
// The bundled synthetic room (data/synthetic_room, exact ground truth) for engine tests.

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/io/ImageSource.h"

namespace voxfuse {

// Its first `count` frames, its calibration and its ground truth.
inline std::vector<RGBDFrame> bundledFrames(int count, RGBDCalib& calib, std::vector<TimedPose>& ground_truth) {
    auto source = openImageSource(std::string(VOXFUSE_SOURCE_DIR) + "/data/synthetic_room");
    calib = source->calib();
    ground_truth = source->groundTruth();
    std::vector<RGBDFrame> frames;
    RGBDFrame frame;
    while (int(frames.size()) < count && source->next(frame)) frames.push_back(std::move(frame));
    return frames;
}

// The ground truth's pose at a frame's time (the bundled room has one per frame).
inline Mat4f groundTruthAt(const std::vector<TimedPose>& ground_truth, double t) {
    for (const TimedPose& p : ground_truth)
        if (std::abs(p.timestamp_s - t) < 1e-4) return p.T_world_camera;
    ADD_FAILURE() << "no ground truth at " << t;
    return Mat4f::identity();
}

// The settings the room's engine tests run with: colour voxels, submaps on or off.
inline MainEngineSettings roomSettings(bool submaps, float submap_distance_m) {
    MainEngineSettings s;
    s.voxel_type = VoxelType::SRgb;
    s.submaps.enabled = submaps;
    s.submaps.max_distance_m = submap_distance_m;
    return s;
}

}  // namespace voxfuse
