#pragma once
// When a frame was taken, as the trackers' motion prediction and the relocaliser's reach measure the
// time between frames.

namespace voxfuse {

// Its timestamp (> 0) or, without one, its index in frames (>= 0); neither: unknown.
struct FrameClock {
    double timestamp_s = 0.0;
    int index = -1;
};

// Seconds from `then` to `now`: by timestamps when both have one, else by indices at 30 frames/s (the
// rate of the cameras this field uses); -1 when unknown or not later.
inline double secondsBetween(FrameClock then, FrameClock now) {
    constexpr double kAssumedFramesPerSecond = 30.0;
    double seconds = -1.0;
    if (then.timestamp_s > 0.0 && now.timestamp_s > 0.0)
        seconds = now.timestamp_s - then.timestamp_s;
    else if (then.index >= 0 && now.index >= 0)
        seconds = double(now.index - then.index) / kAssumedFramesPerSecond;
    return seconds > 0.0 ? seconds : -1.0;
}

}  // namespace voxfuse
