#pragma once
// Tracking with loss detection and relocalisation (docs/DESIGN_NOTES.md, "Relocalisation: detected,
// never fused, found again from keyframes"): the pose of a frame is tracked from the last pose; on the
// frame tracking fails, and on every frame while lost, it is looked up among the keyframes and each
// candidate checked (CandidatePoseCheck.h). Fused, well tracked frames become keyframes when they are
// unlike every keyframe. Without RelocalisationSettings::enabled it only tracks. The main engine owns
// one and hands it the pipeline's state per call (Context).

#include <climits>

#include "CandidatePoseCheck.h"
#include "StageClock.h"
#include "voxfuse/engines/LowLevelEngine.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/engines/RaycastEngine.h"
#include "voxfuse/engines/Relocaliser.h"
#include "voxfuse/engines/Tracker.h"
#include "voxfuse/objects/Scene.h"

namespace voxfuse {

template <class TVoxel, class TIndex>
class RelocalisingTracking {
public:
    struct Context {
        const Scene<TVoxel, TIndex>& scene;
        View& view;                // relocalisation brings the depth's host copy up to date
        const RenderState& model;  // the raycast from the last pose, that tracking aligns to
        Tracker& tracker;
        RaycastEngine<TVoxel, TIndex>& raycast;
        LowLevelEngine& low_level;
        const MainEngineSettings& settings;
        StageClock& clock;
        bool gpu;
        bool map_started;  // a frame was fused, or a map loaded: before that a failed frame is not lost
    };

    RelocalisingTracking(const MainEngineSettings& settings, const RGBDCalib& calib) {
        if (settings.relocalisation.enabled)
            relocaliser_ = std::make_unique<Relocaliser>(settings.relocalisation, calib.depth.size(), settings.device);
    }

    bool enabled() const { return relocaliser_ != nullptr; }
    int keyframeCount() const { return relocaliser_ ? relocaliser_->database().size() : 0; }

    // The frame's pose came from outside: it is not lost.
    void poseGiven(const View& view, FrameResult& result) {
        lost_ = false;
        last_pose_clock_ = view.clock();
        result.keyframes = keyframeCount();
    }

    // The pose of a frame that has none given: tracked from `tracking`'s pose, or looked up among the
    // keyframes (relocalise()). Sets the result's status, relocalisation_tried and keyframes.
    void track(const Context& c, TrackingState& tracking, FrameResult& result) {
        bool found = false;
        if (lost_ && relocaliser_) {
            // Only relocalisation runs: the frame has no verdict of the tracker's own.
            tracking.quality = TrackingQuality::Failed;
            tracking.inlier_ratio = tracking.residual_m = tracking.condition = 0.f;
            if (tracking.translation_constraint >= 0.f) tracking.translation_constraint = 0.f;
        } else {
            const Mat4f T_world_last = tracking.T_world_camera;
            c.tracker.track(tracking, c.view, c.model);
            c.clock.stageDone("track");
            found = tracking.quality != TrackingQuality::Failed;
            if (found && relocaliser_ && relocaliser_->looksLost(tracking)) {
                // Converged, but onto far too little of the model: most likely a wrong pose after a jump.
                tracking.T_world_camera = T_world_last;
                tracking.quality = TrackingQuality::Failed;
                c.tracker.forgetLastPose();
                found = false;
            }
        }
        // A frame with less depth than the tracker needs (a covered lens) is not worth the candidates.
        if (!found && c.map_started && relocaliser_ &&
            c.low_level.countValidDepth(c.view.depth) >= c.settings.tracker.min_inliers) {
            result.relocalisation_tried = true;
            found = relocalise(c, tracking);
            if (!found) c.tracker.forgetLastPose();  // every try's pose was rejected
            c.clock.stageDone("relocalise");
            if (found) result.status = TrackingStatus::Relocalised;
        }
        // Before the map has started (the first frames without depth) a failed frame is not lost: the next
        // one with depth starts the map, as the first frame would have.
        lost_ = !found && c.map_started;
        if (lost_)
            result.status = TrackingStatus::Lost;
        else
            last_pose_clock_ = c.view.clock();
        result.keyframes = keyframeCount();
    }

    // Bookkeeping of a fused, tracked frame: a good one joins the frames loss detection compares with,
    // and becomes a keyframe when it is unlike every keyframe.
    void frameFused(const Context& c, const TrackingState& tracking, FrameResult& result) {
        if (!relocaliser_) return;
        const bool relocalised = result.status == TrackingStatus::Relocalised;
        if (relocalised) relocaliser_->forgetRecentFrames();
        frames_since_relocalisation_ = relocalised ? 0 : frames_since_relocalisation_ + 1;
        if (tracking.quality != TrackingQuality::Good) return;
        relocaliser_->rememberGoodFrame(tracking);
        if (frames_since_relocalisation_ <= c.settings.relocalisation.keyframe_pause_frames) return;
        relocaliser_->addKeyframe(c.view, tracking.T_world_camera);  // the frame's code is made where its images are
        result.keyframes = keyframeCount();
        c.clock.stageDone("keyframes");
    }

    // Loop closure: the pose in this map of a frame that another engine converted (`c.view`), from the
    // keyframes most like it, each refined and checked as a lost frame's candidates are. Nothing of this
    // engine's state changes but the check's raycasts; the tracker's tries are forgotten. Returns
    // whether a candidate passed, its state in `found`.
    bool locate(const typename CandidatePoseCheck<TVoxel, TIndex>::Context& c, TrackingState& found) {
        if (!relocaliser_ || relocaliser_->database().size() == 0) return false;
        bool accepted = false;
        for (const KeyframeMatch& m : relocaliser_->lookUp(c.view)) {
            // Only a keyframe the frame looks like (one that would have kept it from becoming a keyframe
            // itself): unlike a lost frame, a frame that is merely novel here has no claim to be here.
            if (m.dissimilarity >= c.settings.relocalisation.keyframe_min_dissimilarity) continue;
            const Mat4f& T_world_keyframe = relocaliser_->database().keyframe(m.keyframe).T_world_camera;
            // No reach test (elapsed time unknown): the camera comes back after any time.
            if (candidate_check_.refine(c, T_world_keyframe, nullptr, T_world_keyframe, -1.0, found)) {
                accepted = true;
                break;
            }
        }
        c.tracker.forgetLastPose();
        return accepted;
    }

    // The frame in c.view refined from a pose it is believed to be near (`T_world_prior`) and checked
    // as a relocalisation candidate is; no keyframe needed. Nothing is fused; the tracker forgets the pose.
    bool locateNear(const typename CandidatePoseCheck<TVoxel, TIndex>::Context& c, const Mat4f& T_world_prior,
                    TrackingState& found) {
        const bool accepted = candidate_check_.refine(c, T_world_prior, nullptr, T_world_prior, -1.0, found);
        c.tracker.forgetLastPose();
        return accepted;
    }

    // A loaded map: its saved keyframes (those whose codes compare with this relocaliser's), and the
    // next frame is looked up as a lost one is, from the resume pose and then the keyframes: it may be
    // a new recording that starts anywhere in the map, and it must pass relocalisation's check.
    void mapLoaded(const MapKeyframes& saved) {
        forget();
        if (!relocaliser_) return;
        relocaliser_->adoptKeyframes(saved);
        lost_ = true;
    }
    MapKeyframes savedKeyframes() const { return relocaliser_ ? relocaliser_->savedKeyframes() : MapKeyframes(); }
    std::vector<Mat4f> keyframePoses() const {
        std::vector<Mat4f> poses;
        if (relocaliser_)
            for (const Keyframe& k : relocaliser_->database().oldestFirst()) poses.push_back(k.T_world_camera);
        return poses;
    }

    // A new map: no keyframes, not lost, no time of a last good pose.
    void forget() {
        if (relocaliser_) relocaliser_->clear();
        lost_ = false;
        last_pose_clock_ = FrameClock();
        frames_since_relocalisation_ = INT_MAX / 2;
    }

private:
    // Candidate poses for the frame: while lost, the last good pose first (after a short gap the camera
    // is still near it), then those of the keyframes that look most like the frame and that the camera
    // could have reached since (withinReach). The first that passes the check becomes the frame's pose.
    // Returns whether one did; if none did, `tracking` keeps the last good pose.
    bool relocalise(const Context& c, TrackingState& tracking) {
        if (c.gpu) c.view.depth.memory().updateHost();
        // The last good pose is tracked against the raycast from it, which the last good frame left.
        const double elapsed_s = secondsBetween(last_pose_clock_, c.view.clock());
        if (lost_ && refineCandidate(c, tracking.T_world_camera, &c.model, elapsed_s, tracking)) return true;
        for (const KeyframeMatch& m : relocaliser_->lookUp(c.view)) {
            const Mat4f& T_world_keyframe = relocaliser_->database().keyframe(m.keyframe).T_world_camera;
            if (!withinReach(c.settings.relocalisation, tracking.T_world_camera, T_world_keyframe, elapsed_s)) continue;
            if (refineCandidate(c, T_world_keyframe, nullptr, elapsed_s, tracking)) return true;
        }
        return false;
    }

    // One candidate refined and checked; on success it is the frame's tracking state.
    bool refineCandidate(const Context& c, const Mat4f& T_world_start, const RenderState* model, double elapsed_s,
                         TrackingState& tracking) {
        const typename CandidatePoseCheck<TVoxel, TIndex>::Context check{c.scene,   c.view,     c.raycast,
                                                                         c.tracker, c.settings, c.gpu};
        return candidate_check_.refine(check, T_world_start, model, tracking.T_world_camera, elapsed_s, tracking);
    }

    std::unique_ptr<Relocaliser> relocaliser_;  // with RelocalisationSettings::enabled
    bool lost_ = false;           // the last frame had no pose; the tracking state holds the last good one
    FrameClock last_pose_clock_;  // when the frame of that pose was taken (unknown after a reset or load)
    int frames_since_relocalisation_ = INT_MAX / 2;
    CandidatePoseCheck<TVoxel, TIndex> candidate_check_;
};

}  // namespace voxfuse
