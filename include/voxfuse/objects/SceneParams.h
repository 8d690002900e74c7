#pragma once
// Settings of the TSDF volume. Defaults suit a Kinect-class camera indoors.

#include "voxfuse/shared/LabelFusion.h"

namespace voxfuse {

struct SceneParams {
    float voxel_size_m = 0.005f;      // edge length of one voxel
    float mu_m = 0.02f;               // truncation band: SDF values are clamped to [-mu, mu]
    int max_weight = 100;             // depth/colour weights stop growing here (lets the map adapt)
    float view_frustum_min_m = 0.2f;  // depth samples outside [min, max] are ignored
    float view_frustum_max_m = 3.0f;
    bool stop_integrating_at_max_weight = false;            // freeze voxels that reached max_weight
    LabelUpdate label_update = LabelUpdate::Probabilistic;  // semantic voxel types: shared/LabelFusion.h
};

}  // namespace voxfuse
