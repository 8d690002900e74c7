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
    float residual_m = 0.f;    // RMS point-to-plane residual of the inliers (colour tracker: RMS intensity error)
    // Smallest / largest eigenvalue of the tracker's final 6x6 normal matrix (scaled to a unit
    // diagonal): 1 when the six motions are constrained independently, near 0 when the scene leaves
    // some motion unconstrained (a single plane, a corridor).
    float condition = 1.f;
    // Depth trackers: the share of the final full-resolution depth terms' weight along the translation
    // direction they constrain least (0..1/3; see TrackerSettings::poor_translation_constraint): near
    // 0 in a corridor seen without anything facing along it, or facing a single wall. -1 for a tracker
    // without depth terms.
    float translation_constraint = -1.f;
};

}  // namespace voxfuse
