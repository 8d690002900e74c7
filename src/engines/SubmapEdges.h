#pragma once
// The edges SubmapEngine puts into its pose graph (mapping/PoseGraph.h) and how uncertain they are.
// One drift model serves both: RGB-D odometry drifts by about 1% of the distance travelled and a
// degree per metre. A submap is rigid, so a camera far from a submap's origin sees that submap's map
// bent by the drift gathered on the way there.

#include <algorithm>
#include <cmath>

#include "voxfuse/core/Math.h"
#include "voxfuse/mapping/PoseGraph.h"

namespace voxfuse::submap_edges {

constexpr float kDriftPerMetre = 0.01f;
constexpr float kDriftRadPerMetre = 1.f * float(M_PI) / 180.f;
// An odometry edge is at least as uncertain as the tracker's own noise over the overlap frames.
constexpr float kOdometryMinSigmaM = 0.002f;
constexpr float kOdometryMinSigmaRad = 0.2f * float(M_PI) / 180.f;
// A loop edge through a camera at both submaps' origins: an accepted pose tracks the frame with a
// residual under 6 mm and moved less than 1 cm and 1 degree when refined once more
// (RelocalisationSettings).
constexpr float kLoopSigmaM = 0.005f;
constexpr float kLoopSigmaRad = 0.5f * float(M_PI) / 180.f;

inline float distanceM(const Mat4f& T) { return length(T.translation()); }

// Submap `to` started at T_from_to in submap `from`: the drift between from's origin and there.
inline PoseGraphEdge odometry(int from, int to, const Mat4f& T_from_to) {
    PoseGraphEdge e;
    e.from = from;
    e.to = to;
    e.T_from_to = T_from_to;
    const float d = distanceM(T_from_to);
    e.sigma_translation_m = std::max(kOdometryMinSigmaM, kDriftPerMetre * d);
    e.sigma_rotation_rad = std::max(kOdometryMinSigmaRad, kDriftRadPerMetre * d);
    return e;
}

// A loop (or a merge's join): one camera found at T_from_camera in submap `from` and at T_to_camera
// in submap `to`, which places `to` in `from`. Uncertain as an accepted relocalisation is and, apart
// from that, by each submap's drift between its origin and the camera: the graph must not move a
// whole submap by a discrepancy that its own far end gathered.
inline PoseGraphEdge loop(int from, int to, const Mat4f& T_from_camera, const Mat4f& T_to_camera) {
    PoseGraphEdge e;
    e.from = from;
    e.to = to;
    e.T_from_to = T_from_camera * rigidInverse(T_to_camera);
    const float d_from = distanceM(T_from_camera), d_to = distanceM(T_to_camera);
    const auto sum = [](float a, float b, float c) { return std::sqrt(a * a + b * b + c * c); };
    e.sigma_translation_m = sum(kLoopSigmaM, kDriftPerMetre * d_from, kDriftPerMetre * d_to);
    e.sigma_rotation_rad = sum(kLoopSigmaRad, kDriftRadPerMetre * d_from, kDriftRadPerMetre * d_to);
    e.loop = true;
    return e;
}

}  // namespace voxfuse::submap_edges
