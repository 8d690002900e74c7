#pragma once
// Relocalisation's test of one candidate pose (engines/Relocaliser.h says what passes): the tracker refines
// it against the map raycast from it, then once more against the raycast from the refined pose, and the
// frame's depth and colours are compared with the map's seen from there. The main engine asks for it on
// the frames it relocalises; the raycasts it makes here live here.

#include "PoseUpdate.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/engines/RaycastEngine.h"
#include "voxfuse/engines/Relocaliser.h"
#include "voxfuse/engines/Tracker.h"
#include "voxfuse/objects/Scene.h"

namespace voxfuse {

template <class TVoxel, class TIndex>
class CandidatePoseCheck {
public:
    struct Context {
        const Scene<TVoxel, TIndex>& scene;
        const View& view;
        RaycastEngine<TVoxel, TIndex>& raycast;
        Tracker& tracker;
        const MainEngineSettings& settings;
        bool gpu;
    };

    // Refines the candidate T_world_start (against `model`, the raycast from it, or one made here when
    // null) and checks the result, and that the camera could have got there from T_world_last_good in
    // `elapsed_s` (the refinement may slide far from the candidate). Writes `accepted` and returns true
    // when it passes.
    bool refine(const Context& c, const Mat4f& T_world_start, const RenderState* model, const Mat4f& T_world_last_good,
                double elapsed_s, TrackingState& accepted) {
        const RelocalisationSettings& settings = c.settings.relocalisation;
        TrackingState first;
        first.T_world_camera = T_world_start;
        // The first refinement meets the model as tracking does (its resolution, normals from points:
        // a fraction of the cost, and most candidates end here), in a render state of its own (one
        // resized back and forth would be reallocated each time). The check's raycast is at the
        // frame's resolution with SDF normals, valid up to silhouettes, so that inlier ratios are the
        // ones its thresholds were measured with; the gate before it is looser by a fifth, as the
        // coarse model explains less of the frame, also for right candidates.
        if (!model) {
            const int factor = c.settings.tracking_raycast_downsample;
            c.raycast.raycast(c.scene, factor > 1 ? c.view.calib.depth.downsampled(factor) : c.view.calib.depth,
                              T_world_start, coarse_model_, RaycastNormals::FromPoints);
        }
        c.tracker.track(first, c.view, model ? *model : coarse_model_);
        // Too little of the frame explained already: not worth the second refinement.
        if (first.quality != TrackingQuality::Good || first.inlier_ratio < 0.8f * settings.min_inlier_ratio)
            return false;
        c.raycast.raycast(c.scene, c.view.calib.depth, first.T_world_camera, model_);
        RelocalisationCheck check;
        check.refined = first;
        c.tracker.track(check.refined, c.view, model_);
        pose::motionBetween(pose::toEigenD(first.T_world_camera), pose::toEigenD(check.refined.T_world_camera),
                            check.step_m, check.step_deg);
        if (c.gpu) model_.updateHost();
        raycastDepth(model_, depth_);
        check.depth = compareDepth(c.view.depth, depth_, settings.agreement_tolerance_m);
        if (!acceptRelocalisation(settings, check)) return false;
        if (!withinReach(settings, T_world_last_good, check.refined.T_world_camera, elapsed_s)) return false;
        // Geometry and reach first: only a candidate they take is rendered in colour and compared.
        check.color = compareCandidateColor(c);
        if (!acceptRelocalisation(settings, check)) return false;
        accepted = check.refined;
        return true;
    }

private:
    // The frame's colours against the map's, seen from the candidate (model_ and depth_); not compared
    // where either has none.
    ColorAgreement compareCandidateColor(const Context& c) {
        if constexpr (!TVoxel::hasColor) {
            return ColorAgreement{};
        } else {
            if (c.view.rgb.empty()) return ColorAgreement{};
            c.raycast.renderIntensity(c.scene, model_, intensity_);
            if (c.gpu) intensity_.memory().updateHost();
            return compareColor(c.view, depth_, intensity_, c.settings.relocalisation.agreement_tolerance_m,
                                c.settings.scene.voxel_size_m);
        }
    }

    RenderState coarse_model_;  // the model raycast from the candidate, as tracking sees it
    RenderState model_;         // and from its refined pose at full resolution, for the check
    Image<float> depth_;
    Image<float> intensity_;  // the map's colours seen from it (colour voxel types)
};

}  // namespace voxfuse
