#pragma once
// Internal: the hand-over between ThreadedImageSource's reader thread and its consumer. A bounded
// FIFO of frames, frame errors and the end mark, which either makes the reader wait for room or
// drops the oldest entry, and which can be closed to release a waiting reader. Its places are made
// up front, so that handing an entry over never allocates: a reader thread cannot fail on the way
// and leave the consumer waiting for an end mark that never comes.

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <mutex>
#include <vector>

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
        : capacity_(capacity), drop_oldest_(drop_oldest_when_full), slots_(capacity + 1) {}  // + 1: the end mark

    // Reader side. Frames and errors take a place each; the end mark always goes in at once, so that
    // the reader can finish (a reader gives one end mark, its last entry). Returns false, dropping the
    // entry, once the queue is closed.
    bool push(QueuedFrame entry) {
        std::unique_lock<std::mutex> lock(mutex_);
        if (entry.kind != QueuedFrame::Kind::End) {
            if (drop_oldest_) {
                if (count_ >= capacity_ && count_ > 0) {
                    takeFront();
                    ++dropped_;
                }
            } else {
                not_full_.wait(lock, [&] { return closed_ || count_ < capacity_; });
            }
        }
        if (closed_) return false;
        slots_[(front_ + count_) % slots_.size()] = std::move(entry);
        ++count_;
        not_empty_.notify_one();
        return true;
    }

    // Consumer side: waits for the next entry.
    QueuedFrame pop() {
        std::unique_lock<std::mutex> lock(mutex_);
        not_empty_.wait(lock, [&] { return count_ > 0; });
        QueuedFrame entry = takeFront();
        not_full_.notify_one();
        return entry;
    }

    // Consumer side: whether an entry is there, waiting for one at most `timeout`.
    bool waitForEntry(std::chrono::milliseconds timeout) {
        std::unique_lock<std::mutex> lock(mutex_);
        return not_empty_.wait_for(lock, timeout, [&] { return count_ > 0; });
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
    QueuedFrame takeFront() {
        QueuedFrame entry = std::move(slots_[front_]);
        slots_[front_] = QueuedFrame{};  // the frame's images go with the entry, not stay in the slot
        front_ = (front_ + 1) % slots_.size();
        --count_;
        return entry;
    }

    const std::size_t capacity_;
    const bool drop_oldest_;
    mutable std::mutex mutex_;
    std::condition_variable not_empty_, not_full_;
    std::vector<QueuedFrame> slots_;  // a ring: count_ entries from front_ on
    std::size_t front_ = 0, count_ = 0;
    bool closed_ = false;
    long dropped_ = 0;
};

}  // namespace voxfuse
