#pragma once
// Where the camera is and how sure we are of it.

#include "voxfuse/core/Math.h"

namespace voxfuse {

enum class TrackingQuality { Good, Poor, Failed };

inline const char* toString(TrackingQuality q) {
    return q == TrackingQuality::Good ? "good" : q == TrackingQuality::Poor ? "poor" : "failed";
}

struct TrackingState {
    Mat4f T_world_camera = Mat4f::identity();  // pose of the depth camera
    TrackingQuality quality = TrackingQuality::Good;
    float inlier_ratio = 1.f;  // fraction of valid pixels that found a model correspondence
    float residual_m = 0.f;    // RMS point-to-plane residual of the inliers
};

}  // namespace voxfuse
