#pragma once
// When a frame was taken, as the trackers' motion prediction and the relocaliser's reach measure the
// time between frames.

namespace voxfuse {

// Its timestamp (> 0) or, without one, its index in frames (>= 0); neither: unknown.
struct FrameClock {
    double timestamp_s = 0.0;
    int index = -1;
};

}  // namespace voxfuse
