#pragma once
// Internal: the hand-over between ThreadedImageSource's reader thread and its consumer. A bounded
// FIFO of frames, frame errors and the end mark, which either makes the reader wait for room or
// drops the oldest entry, and which can be closed to release a waiting reader.

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <mutex>

#include "voxfuse/io/RGBDFrame.h"

namespace voxfuse {

struct QueuedFrame {
    enum class Kind { Frame, Error, End };
    Kind kind = Kind::End;
    RGBDFrame frame;           // Kind::Frame
    std::exception_ptr error;  // Kind::Error: what the source threw for this frame
};

class BoundedFrameQueue {
public:
    BoundedFrameQueue(std::size_t capacity, bool drop_oldest_when_full)
        : capacity_(capacity), drop_oldest_(drop_oldest_when_full) {}

    // Reader side. Frames and errors take a place each; the end mark always goes in at once, so that
    // the reader can finish. Returns false, dropping the entry, once the queue is closed.
    bool push(QueuedFrame entry) {
        std::unique_lock<std::mutex> lock(mutex_);
        if (entry.kind != QueuedFrame::Kind::End) {
            if (drop_oldest_) {
                if (entries_.size() >= capacity_ && !entries_.empty()) {
                    entries_.pop_front();
                    ++dropped_;
                }
            } else {
                not_full_.wait(lock, [&] { return closed_ || entries_.size() < capacity_; });
            }
        }
        if (closed_) return false;
        entries_.push_back(std::move(entry));
        not_empty_.notify_one();
        return true;
    }

    // Consumer side: waits for the next entry.
    QueuedFrame pop() {
        std::unique_lock<std::mutex> lock(mutex_);
        not_empty_.wait(lock, [&] { return !entries_.empty(); });
        QueuedFrame entry = std::move(entries_.front());
        entries_.pop_front();
        not_full_.notify_one();
        return entry;
    }

    // Refuses later pushes and wakes a reader waiting for room.
    void close() {
        std::lock_guard<std::mutex> lock(mutex_);
        closed_ = true;
        not_full_.notify_all();
    }

    long dropped() const {
        std::lock_guard<std::mutex> lock(mutex_);
        return dropped_;
    }

private:
    const std::size_t capacity_;
    const bool drop_oldest_;
    mutable std::mutex mutex_;
    std::condition_variable not_empty_, not_full_;
    std::deque<QueuedFrame> entries_;
    bool closed_ = false;
    long dropped_ = 0;
};

}  // namespace voxfuse
