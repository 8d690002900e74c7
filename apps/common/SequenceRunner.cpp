#include "SequenceRunner.h"

#include <iostream>

#include "voxfuse/core/Error.h"
#include "voxfuse/io/CalibPlausibility.h"

namespace voxfuse::app {

SequenceRunner::SequenceRunner(ImageSource& source, MainEngine& engine, PoseSource poses, RunRecord& record,
                               const char* program)
    : source_(source), engine_(engine), poses_(poses), record_(record), program_(program) {
    if (poses_ == PoseSource::GroundTruth && source_.groundTruth().empty())
        throw ConfigError("poses from ground truth need a source with ground truth, and '" + source_.description() +
                          "' has none");
}

int SequenceRunner::skip(int count) {
    int skipped = 0;
    for (; skipped < count; ++skipped) {
        try {
            if (!source_.next(frame_)) break;
        } catch (const IoError&) {
            // An unreadable frame is skipped all the same.
        }
    }
    return skipped;
}

bool SequenceRunner::processNext(const std::function<bool()>& stop) {
    for (;;) {
        if (stop()) return false;
        const Step result = step();
        if (result != Step::Skipped) return result == Step::Processed;
    }
}

SequenceRunner::Step SequenceRunner::step() {
    try {
        if (!source_.next(frame_)) return Step::End;
    } catch (const IoError& e) {
        ++record_.frames_unreadable;
        std::cerr << "\n" << program_ << ": skipping unreadable frame: " << e.what() << "\n";
        return Step::Skipped;
    }
    reportSamplesOutOfRange();
    Mat4f pose;
    const Mat4f* given = nullptr;
    if (poses_ == PoseSource::GroundTruth) {
        if (!frame_.has_ground_truth) {
            ++record_.frames_without_pose;
            return Step::Skipped;
        }
        if (!have_origin_) {
            // The world is the first frame's camera, or the one of the map the engine continues.
            Mat4f T_source_world = frame_.T_world_camera_gt;
            if (!engine_.sourceOrigin(T_source_world)) engine_.setSourceOrigin(T_source_world);
            T_origin_world_ = rigidInverse(T_source_world);
            have_origin_ = true;
        }
        pose = T_origin_world_ * frame_.T_world_camera_gt;
        given = &pose;
    }
    FrameRecord fr;
    fr.index = frame_.index;
    fr.timestamp_s = frame_.timestamp_s;
    fr.result = engine_.processFrame(frame_, given);
    reportFullMap(fr.result);
    reportNoColorToTrack();
    record_.frames.push_back(fr);
    // A lost frame has no pose (it holds the last good one): the trajectory leaves it out.
    if (fr.result.status != TrackingStatus::Lost)
        record_.trajectory.push_back({frame_.timestamp_s, fr.result.T_world_camera});
    return Step::Processed;
}

// Samples above the maximum their file declares, or depth the calibration maps to no depth, are invalid:
// depth is read as no measurement, colour as full intensity; counted, and said per frame (the first few
// frames; then the count in the summary).
void SequenceRunner::reportSamplesOutOfRange() {
    const RGBDCalib& calib = source_.calib();  // the engine's (view() would copy the view back from a GPU)
    const std::size_t above_maxval = frame_.depth_samples_out_of_range;
    const std::size_t without_depth = depthSamplesWithoutDepth(frame_.depth_raw, calib.disparity, calib.depth.fx);
    const std::size_t color_above_maxval = frame_.color_samples_out_of_range;
    if (above_maxval + without_depth + color_above_maxval == 0) return;
    record_.depth_samples_out_of_range += (long long)(above_maxval + without_depth);
    record_.color_samples_out_of_range += (long long)color_above_maxval;
    constexpr int kFramesSaid = 10;
    if (++record_.frames_with_samples_out_of_range > kFramesSaid) return;
    std::cerr << "\n" << program_ << ": warning: frame " << frame_.index << ": ";
    if (color_above_maxval > 0)
        std::cerr << color_above_maxval << " colour samples exceed the maximum the colour file declares (read as full "
                  << "intensity)" << (above_maxval + without_depth > 0 ? "; " : "");
    if (above_maxval + without_depth > 0) std::cerr << frame_.depth_path << ": ";
    if (above_maxval > 0) std::cerr << above_maxval << " depth samples exceed the maximum the file declares";
    if (above_maxval > 0 && without_depth > 0) std::cerr << " and ";
    if (without_depth > 0)
        std::cerr << without_depth << " depth samples lie where the calibration's depth conversion gives no depth";
    if (above_maxval + without_depth > 0) std::cerr << "; they are read as no measurement";
    std::cerr << (record_.frames_with_samples_out_of_range == kFramesSaid
                      ? " (said for the first " + std::to_string(kFramesSaid) + " such frames; summary.json counts all)"
                      : std::string())
              << "\n";
}

// The colour tracker has nothing to go on in a frame without colour: said once, with the remedy,
// since the frame's only other sign is a failed track.
void SequenceRunner::reportNoColorToTrack() {
    if (reported_no_color_ || !frame_.rgb.empty() || poses_ == PoseSource::GroundTruth ||
        engine_.settings().tracker.kind != TrackerKind::Color)
        return;
    reported_no_color_ = true;
    std::cerr << "\n"
              << program_ << ": warning: frame " << frame_.index
              << " has no colour image, and the colour tracker (--tracker color) follows colour alone: such frames "
                 "cannot be tracked. "
                 "Use --tracker ren (depth) or rgbd (depth, and colour where there is any).\n";
}

// Said when it happens: from then on the parts of the scene the map has no room for are not fused,
// and tracking against a model with holes may fail. Each cause once.
void SequenceRunner::reportFullMap(const FrameResult& result) {
    const AllocationStats& a = result.allocation;
    const bool blocks_full = a.failures_blocks_full_this_frame > 0 && !reported_blocks_full_;
    const bool hash_full = a.failures_hash_full_this_frame > 0 && !reported_hash_full_;
    if (!blocks_full && !hash_full) return;  // every frame comes here: no text made for nothing
    const std::string frame = std::string(program_) + ": warning: frame " + std::to_string(frame_.index) + ": ";
    const std::string effect =
        " of the blocks this frame's depth needs could not be allocated; what they hold is not fused (nor, from "
        "now on, anything else the map has no room for) and tracking may fail. ";
    if (blocks_full) {
        reported_blocks_full_ = true;
        std::cerr << "\n"
                  << frame << "the map is full (" << engine_.settings().hash.max_block_count
                  << " voxel blocks, its most): " << a.failures_blocks_full_this_frame << effect
                  << (engine_.settings().swap.enabled
                          ? "Give swapping more active blocks (--active-blocks) or use larger voxels (--voxel-size).\n"
                          : "Use swapping (--swap), a larger --max-blocks or larger voxels (--voxel-size).\n");
    }
    if (hash_full) {
        reported_hash_full_ = true;
        std::cerr << "\n"
                  << frame
                  << "the hash table is full (every bucket and excess entry taken): " << a.failures_hash_full_this_frame
                  << effect << "Use more --hash-buckets and --hash-excess, or larger voxels (--voxel-size).\n";
    }
}

}  // namespace voxfuse::app
