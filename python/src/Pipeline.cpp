#include "Pipeline.h"

#include "voxfuse/core/Error.h"
#include "voxfuse/engines/TrackerSettings.h"

namespace voxfuse::python {

MainEngineSettings PipelineSettings::toEngineSettings() const {
    MainEngineSettings s;
    s.voxel_type = parseVoxelType(voxel);
    s.index_type = parseIndexType(index);
    if (device != "cpu" && device != "cuda") throw ConfigError("device: 'cpu' or 'cuda', not '" + device + "'");
    s.device = device == "cuda" ? Device::CUDA : Device::CPU;
    s.scene.voxel_size_m = voxel_size;
    s.scene.mu_m = mu;
    s.scene.max_weight = max_weight;
    s.scene.view_frustum_min_m = min_depth;
    s.scene.view_frustum_max_m = max_depth;
    s.depth_gap_tolerance = depth_gap_tolerance;
    if (label_update != "probabilistic" && label_update != "vote")
        throw ConfigError("label_update: 'probabilistic' or 'vote', not '" + label_update + "'");
    s.scene.label_update = label_update == "vote" ? LabelUpdate::Vote : LabelUpdate::Probabilistic;
    s.hash.max_block_count = max_blocks;
    s.hash.bucket_count = hash_buckets;
    s.hash.excess_entry_count = hash_excess;
    if (volume_size.size() != 3 || volume_offset.size() != 3)
        throw ConfigError("volume_size and volume_offset take three numbers (x, y, z)");
    s.dense_size = {volume_size[0], volume_size[1], volume_size[2]};
    s.dense_offset = {volume_offset[0], volume_offset[1], volume_offset[2]};
    s.tracker = trackerSettingsWith(
        {tracker_config, tracker, tracker_levels, tracker_iterations, tracker_max_distance, "Pipeline settings"});
    s.swap.enabled = swap || active_blocks > 0 || !swap_file.empty();
    s.swap.swap_file = swap_file;
    s.swap.blocks_per_frame = swap_blocks_per_frame;
    if (active_blocks < 0) throw ConfigError("active_blocks must not be negative");
    if (active_blocks > 0) s.hash.max_block_count = active_blocks;
    s.relocalisation.enabled = relocalise;
    s.relocalisation.candidates = relocalise_candidates;
    s.relocalisation.max_speed_m_per_s = relocalise_max_speed;
    s.relocalisation.min_color_correlation = relocalise_min_color_correlation;
    return s;
}

void PipelineSettings::adopt(const MapFileInfo& info) {
    const MainEngineSettings s = settingsForMap(info, toEngineSettings());
    voxel = info.voxel_type;
    index = info.hash ? "hash" : "dense";
    voxel_size = s.scene.voxel_size_m;
    mu = s.scene.mu_m;
    max_blocks = s.hash.max_block_count;
    hash_buckets = s.hash.bucket_count;
    hash_excess = s.hash.excess_entry_count;
    volume_size = {s.dense_size.x, s.dense_size.y, s.dense_size.z};
    volume_offset = {s.dense_offset.x, s.dense_offset.y, s.dense_offset.z};
}

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
