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
    // `program` names the front-end in what the run says on stderr.
    SequenceRunner(ImageSource& source, MainEngine& engine, PoseSource poses, RunRecord& record, const char* program);

    enum class Step {
        Processed,  // the next frame was read and processed
        Skipped,    // it could not be read, or lacks the ground-truth pose poses come from: counted in the record
        End         // the source has no more frames
    };
    // Reads the next frame and processes it. After Skipped the caller calls again: a GUI gets back to
    // its events in between, so that a camera which stopped delivering (an error every few seconds)
    // does not hold it.
    Step step();
    // step() until a frame was processed (true), or the source ended or `stop` says so (false).
    bool processNext(const std::function<bool()>& stop);
    // Reads and drops the next `count` frames (a run that continues a map saved after them). Returns
    // how many there were.
    int skip(int count);
    // The frame last processed (valid after Step::Processed).
    const RGBDFrame& frame() const { return frame_; }
    const FrameRecord& lastRecord() const { return record_.frames.back(); }

private:
    void reportNoColorToTrack();
    void reportSamplesOutOfRange();
    void reportFullMap(const FrameResult& result);

    ImageSource& source_;
    MainEngine& engine_;
    PoseSource poses_;
    RunRecord& record_;
    const char* program_;
    RGBDFrame frame_;
    bool have_origin_ = false;
    Mat4f T_origin_world_ = Mat4f::identity();
    bool reported_blocks_full_ = false, reported_hash_full_ = false, reported_no_color_ = false;
};

}  // namespace voxfuse::app
