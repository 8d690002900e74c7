#include "SequenceRunner.h"

#include <iostream>

#include "voxfuse/core/Error.h"

namespace voxfuse::app {

SequenceRunner::SequenceRunner(ImageSource& source, MainEngine& engine, PoseSource poses, RunRecord& record)
    : source_(source), engine_(engine), poses_(poses), record_(record) {
    if (poses_ == PoseSource::GroundTruth && source_.groundTruth().empty())
        throw ConfigError("poses from ground truth need a source with ground truth, and '" + source_.description() + "' has none");
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

bool SequenceRunner::step() {
    for (;;) {
        try {
            if (!source_.next(frame_)) return false;
        } catch (const IoError& e) {
            ++record_.frames_unreadable;
            std::cerr << "\nvoxfuse: skipping unreadable frame: " << e.what() << "\n";
            continue;
        }
        Mat4f pose;
        const Mat4f* given = nullptr;
        if (poses_ == PoseSource::GroundTruth) {
            if (!frame_.has_ground_truth) {
                ++record_.frames_without_pose;
                continue;
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
        record_.frames.push_back(fr);
        // A lost frame has no pose (it holds the last good one): the trajectory leaves it out.
        if (fr.result.status != TrackingStatus::Lost) record_.trajectory.push_back({frame_.timestamp_s, fr.result.T_world_camera});
        return true;
    }
}

}  // namespace voxfuse::app
