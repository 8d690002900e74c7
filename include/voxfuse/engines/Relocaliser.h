#pragma once
// Finding the camera again after tracking was lost. While tracking is good, frames whose fern codes
// (engines/FernEncoder.h) differ from every stored keyframe become keyframes (engines/KeyframeDatabase.h).
// Once lost, a frame's code is looked up and the poses of the nearest keyframes are candidates:
// MainEngine refines each by the tracker against the model raycast from it and takes one only when
// acceptRelocalisation() holds, a stricter test than the tracker's own, so that a wrong pose is
// never fused. Host code; on the GPU the frame's depth is brought to the host to be encoded.

#include <memory>
#include <vector>

#include "voxfuse/engines/FernEncoder.h"
#include "voxfuse/engines/KeyframeDatabase.h"
#include "voxfuse/io/MapFile.h"
#include "voxfuse/objects/FrameClock.h"
#include "voxfuse/objects/TrackingState.h"
#include "voxfuse/objects/View.h"

namespace voxfuse {

struct RelocalisationSettings {
    bool enabled = true;
    // Loss detection beyond the tracker's own failure: a frame tracked with an inlier ratio below this
    // fraction of the median of the last recent_frames good frames is taken as lost (a jump the tracker
    // "converged" from into a wrong pose: the inlier ratio then falls to a fraction of its usual value).
    float lost_inlier_ratio_drop = 0.5f;
    int recent_frames = 10;
    FernSettings ferns;
    int max_keyframes = 1000;
    float keyframe_min_dissimilarity = 0.2f;  // a frame this dissimilar from every keyframe becomes one
    int keyframe_pause_frames =
        10;              // frames after a relocalisation that are not made keyframes (their pose is the least sure)
    int candidates = 3;  // keyframes tried per lost frame, nearest codes first (the last good pose is tried too)
    // A keyframe farther from the last good pose than this speed covers in the time since that frame is
    // not a candidate, nor is a refined pose that far: the camera cannot be there, however alike the
    // views (a corridor's repeating walls, a row of equal desks). 9 m/s is the tracker's own limit
    // (max_motion_m, 0.3 m per frame, at 30 frames/s); hand-held and robot cameras move far slower.
    // 0: no limit.
    float max_speed_m_per_s = 9.f;

    // Acceptance (all must hold), measured after a second refinement from the refined pose against the
    // model raycast from there.
    float min_inlier_ratio = 0.5f;  // the tracker's inliers / valid frame pixels
    float max_residual_m = 0.006f;  // the tracker's RMS point-to-plane residual
    float min_overlap = 0.5f;       // valid frame pixels where the model has depth, of all valid frame pixels
    float min_agreement = 0.75f;    // of those, the ones whose depths differ by less than agreement_tolerance_m
    float agreement_tolerance_m = 0.02f;
    float max_refinement_step_m = 0.01f;  // the second refinement moves the pose less than this: it had converged
    float max_refinement_step_deg = 1.f;
    // Where the map and the frame have colour: the correlation of the frame's intensities with the
    // model's fused colours, over the pixels whose depths agree (compareColor). Geometry alone takes
    // a mirror-symmetric or repeating place for another; its colours tell them apart.
    float min_color_correlation = 0.5f;
};

// How a frame's depth agrees with the model's depth seen from the same pose (both in metres, 0 = none).
struct DepthAgreement {
    float overlap = 0.f;    // valid frame pixels where the model has depth / valid frame pixels
    float agreement = 0.f;  // of the pixels both have, those within the tolerance
};
DepthAgreement compareDepth(const Image<float>& frame_depth_m, const Image<float>& model_depth_m, float tolerance_m);

// How a frame's colours agree with the model's fused colours seen from the same pose. The depth
// image is cut into cells (kColorCellsAcross across); in each, the normalised cross-correlation
// (zero mean, so that exposure and gain do not count) of the two intensities over the frame's depth
// pixels whose depth agrees with the model's within `tolerance_m` (no occluders), which the colour
// camera sees and where the map has colour; then the mean over the cells, weighed by their pixels.
// Cells compare texture, not where bright and dark regions lie, which the same shape under other
// colours often shares.
// `model_intensity` is the map's colour as intensities in [0, 1] (RaycastEngine::renderIntensity) at
// the raycast that gave `model_depth_m`, in the depth camera; -1 where no voxel saw colour. It holds
// no detail finer than the map's voxels (`voxel_size_m`; 0 compares single colour pixels): the
// render interpolates between voxels. So the frame's intensity is its mean over the footprint of
// kColorFootprintVoxels voxels at the pixel's depth (the nearest colour pixel where that is
// narrower than one), and texture that only the frame resolves (a colour camera finer than the map)
// is not taken for disagreement. No verdict (`compared` false) without colour on either side, or
// with fewer than `min_textured_cells` cells that have both pixels and texture on both sides (plain
// walls correlate with nothing).
constexpr int kColorCellsAcross = 16;
constexpr int kColorCellMinPixels = 8;
constexpr float kColorFootprintVoxels = 1.5f;  // a trilinear read's spread, as a box
struct ColorAgreement {
    bool compared = false;
    float correlation = 0.f;  // in [-1, 1] when compared
    int cells = 0;            // that had their say
    int pixels = 0;           // in them
};
ColorAgreement compareColor(const View& view, const Image<float>& model_depth_m, const Image<float>& model_intensity,
                            float tolerance_m, float voxel_size_m, int min_textured_cells = 8);

// What acceptance looks at for one candidate.
struct RelocalisationCheck {
    TrackingState refined;  // the second refinement's verdict and pose
    float step_m = 0.f;     // how far the second refinement moved the pose
    float step_deg = 0.f;
    DepthAgreement depth;  // at the first refinement's pose, against the raycast from there
    ColorAgreement color;  // the same, for colour (not compared: no colour test)
};
bool acceptRelocalisation(const RelocalisationSettings& settings, const RelocalisationCheck& check);

// Whether a camera at T_world_last `elapsed_s` ago (-1: unknown) may be at T_world_candidate now, at
// settings.max_speed_m_per_s. Unknown times and a limit of 0 allow every candidate.
bool withinReach(const RelocalisationSettings& settings, const Mat4f& T_world_last, const Mat4f& T_world_candidate,
                 double elapsed_s);

class Relocaliser {
public:
    // For frames of `frame_size` (the depth camera's).
    // Frames are averaged down for their codes on `device` (FernEncoder), where the pipeline keeps them.
    Relocaliser(const RelocalisationSettings& settings, Vec2i frame_size, Device device = Device::CPU);
    ~Relocaliser();

    // Whether a frame the tracker did not fail is still implausible (see lost_inlier_ratio_drop)...
    bool looksLost(const TrackingState& tracked) const;
    // ... against the recent good frames given here; forgotten after a relocalisation, as the camera
    // may be somewhere else entirely.
    void rememberGoodFrame(const TrackingState& tracked);
    void forgetRecentFrames() { recent_inlier_ratios_.clear(); }
    // Keyframe bookkeeping of a well-tracked frame (its depth in host memory): stored when novel.
    // Returns whether it became a keyframe.
    bool addKeyframe(const View& view, const Mat4f& T_world_camera);
    // The keyframes whose codes are nearest to the frame's, nearest first (at most settings.candidates).
    std::vector<KeyframeMatch> lookUp(const View& view);

    const KeyframeDatabase& database() const { return database_; }
    // The keyframes as a map file saves them (io/MapFile.h)...
    MapKeyframes savedKeyframes() const;
    // ... and a map's saved keyframes in place of this relocaliser's. They are taken only where their
    // codes compare with the ones this relocaliser makes: the same fern settings and frame size, and
    // codes of the same kind (with or without intensity; where no frame was encoded yet, the codes are
    // made of the saved keyframes' kind from then on). Returns whether they were taken.
    bool adoptKeyframes(const MapKeyframes& saved);
    const RelocalisationSettings& settings() const { return settings_; }
    // Forgets every keyframe and the recent frames (a new map).
    void clear();

private:
    FernCode encode(const View& view);

    RelocalisationSettings settings_;
    Vec2i frame_size_;
    Device device_;
    std::unique_ptr<FernEncoder> encoder_;  // made for the first frame encoded: with intensity when it has colour
    KeyframeDatabase database_;
    // Saved keyframes taken before any frame was encoded: their kind (0/1), which the encoder takes.
    int adopted_intensity_ = -1;
    std::vector<float> recent_inlier_ratios_;  // of the last good frames, oldest first
};

}  // namespace voxfuse
