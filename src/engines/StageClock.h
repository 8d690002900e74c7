#pragma once
// The main engine's per-frame stage times (FrameResult::stages).

#include <chrono>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/MainEngine.h"

namespace voxfuse {

// The frame's stage times: wall clock on the CPU; on the GPU, CUDA events recorded at the stage
// boundaries, read once the frame's work has finished (no synchronisation between stages).
class StageClock {
public:
    static constexpr int kMaxStages = 10;
    explicit StageClock(bool gpu) : gpu_(gpu) {
        if (gpu_)
            for (void*& e : events_) e = device_memory::createEvent();
    }
    ~StageClock() {
        for (void* e : events_) device_memory::destroyEvent(e);
    }
    StageClock(const StageClock&) = delete;
    StageClock& operator=(const StageClock&) = delete;

    void start(FrameResult& result) {
        result_ = &result;
        marks_ = 0;
        mark();
    }
    // The stage that ran since the last mark ends here.
    void stageDone(const char* name) {
        mark();
        result_->stages.push_back({name, 0.0});
    }
    // Fills in the stage times (waiting for the GPU's work on the GPU).
    void finish() {
        for (int i = 1; i < marks_; ++i)
            result_->stages[std::size_t(i - 1)].ms =
                gpu_ ? double(device_memory::eventElapsedMs(events_[i - 1], events_[i]))
                     : std::chrono::duration<double, std::milli>(times_[i] - times_[i - 1]).count();
    }

private:
    void mark() {
        if (marks_ >= kMaxStages + 1) throw Error("StageClock: more stages than it can time");
        if (gpu_)
            device_memory::recordEvent(events_[marks_]);
        else
            times_[marks_] = std::chrono::steady_clock::now();
        ++marks_;
    }

    bool gpu_;
    void* events_[kMaxStages + 1] = {};
    std::chrono::steady_clock::time_point times_[kMaxStages + 1];
    int marks_ = 0;
    FrameResult* result_ = nullptr;
};

}  // namespace voxfuse
