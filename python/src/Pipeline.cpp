#include "Pipeline.h"

#include "voxfuse/core/Error.h"

namespace voxfuse::python {

Pipeline::Pipeline(const RGBDCalib& calib, const PipelineSettings& settings)
    : calib_(calib), settings_(settings), engine_(MainEngine::create(settings.toEngineSettings(), calib)) {}

FrameResult Pipeline::process(const RGBDFrame& frame, const Mat4f* T_world_camera_given) {
    FrameResult r = engine_->processFrame(frame, T_world_camera_given);
    ++frames_;
    fused_ += r.fused;
    failed_ += r.quality == TrackingQuality::Failed;
    poor_ += r.quality == TrackingQuality::Poor;
    lost_ += r.status == TrackingStatus::Lost;
    relocalisation_attempts_ += r.relocalisation_tried;
    relocalisations_ += r.status == TrackingStatus::Relocalised;
    // A lost frame holds the last good pose, not its own: like the CLI's trajectory, leave it out.
    if (r.status != TrackingStatus::Lost) trajectory_.push_back({frame.timestamp_s, r.T_world_camera});
    for (const StageTime& st : r.stages) stage_times_[st.stage].ms.push_back(st.ms);
    stage_times_["total"].ms.push_back(r.total_ms);
    return r;
}

Mat4f Pipeline::groundTruthPose(const RGBDFrame& frame) {
    if (!frame.has_ground_truth)
        throw ConfigError("frame " + std::to_string(frame.index) + " has no ground-truth pose");
    if (!have_origin_) {
        Mat4f T_source_world = frame.T_world_camera_gt;
        if (!engine_->sourceOrigin(T_source_world)) engine_->setSourceOrigin(T_source_world);
        T_origin_world_ = rigidInverse(T_source_world);
        have_origin_ = true;
    }
    return T_origin_world_ * frame.T_world_camera_gt;
}

std::vector<TimedPose> Pipeline::optimisedTrajectory() {
    std::vector<Mat4f> T_world_camera;
    if (!engine_->optimisedPoses(T_world_camera)) return trajectory_;
    return withPoses(trajectory_, T_world_camera);
}

std::unique_lock<std::mutex> Pipeline::claim(const char* call) {
    std::unique_lock<std::mutex> lock(busy_, std::try_to_lock);
    if (!lock)
        throw Error(std::string("Pipeline.") + call +
                    ": the pipeline is in use by another thread (one call at a time per pipeline)");
    return lock;
}

void Pipeline::reset() {
    have_origin_ = false;
    engine_->reset();
    trajectory_.clear();
    stage_times_.clear();
    frames_ = fused_ = failed_ = poor_ = 0;
    lost_ = relocalisation_attempts_ = relocalisations_ = 0;
}

}  // namespace voxfuse::python
