#pragma once
// Drives a MainEngine over an ImageSource one frame at a time, the way every front-end needs it:
// unreadable frames are reported and skipped, ground-truth poses are re-expressed relative to the
// first one (the first camera defines the world, as with tracking; a map the engine loaded keeps its
// own world), and each frame's result is recorded. The first frame that finds the hash map full is
// reported on stderr (the summary only counts the blocks that could not be allocated, at the end).

#include <functional>
#include <string>

#include "RunRecord.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/io/ImageSource.h"

namespace voxfuse::app {

enum class PoseSource { GroundTruth, Tracker };

class SequenceRunner {
public:
    SequenceRunner(ImageSource& source, MainEngine& engine, PoseSource poses, RunRecord& record);

    // Reads and processes the next frame. Returns false at the end of the source. Frames that cannot
    // be read, or that lack a ground-truth pose when poses come from ground truth, are counted in the
    // record and skipped (the call moves on to the next frame).
    bool step();
    // Reads and drops the next `count` frames (a run that continues a map saved after them). Returns
    // how many there were.
    int skip(int count);
    // The frame last processed (valid after step() returned true).
    const RGBDFrame& frame() const { return frame_; }
    const FrameRecord& lastRecord() const { return record_.frames.back(); }

private:
    void reportNoColourToTrack();
    void reportFullMap(const FrameResult& result);

    ImageSource& source_;
    MainEngine& engine_;
    PoseSource poses_;
    RunRecord& record_;
    RGBDFrame frame_;
    bool have_origin_ = false;
    Mat4f T_origin_world_ = Mat4f::identity();
    bool reported_blocks_full_ = false, reported_hash_full_ = false, reported_no_colour_ = false;
};

}  // namespace voxfuse::app
