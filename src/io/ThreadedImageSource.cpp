// The input thread: decodes and undistorts frames ahead of the engine.

#include "voxfuse/io/ThreadedImageSource.h"

#include <thread>

#include "BoundedFrameQueue.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/UndistortedImageSource.h"

namespace voxfuse {

namespace {

bool dropsWhenFull(const ThreadedSourceOptions& options, const ImageSource& source) {
    switch (options.when_full) {
        case ThreadedSourceOptions::WhenFull::Wait:
            return false;
        case ThreadedSourceOptions::WhenFull::DropOldest:
            return true;
        case ThreadedSourceOptions::WhenFull::Automatic:
            break;
    }
    return source.isLive();
}

// The source the reader thread reads: undistorting when asked to (io/UndistortedImageSource.h), so
// that the remapping runs on the reader thread too.
std::unique_ptr<ImageSource> readerSource(std::unique_ptr<ImageSource> source, const ThreadedSourceOptions& options) {
    if (!source) throw ConfigError("ThreadedImageSource: no source given");
    return options.undistort ? undistorted(std::move(source)) : std::move(source);
}

}  // namespace

// Everything the two threads share. The source's properties are copied at construction, so that
// the consumer's queries never touch the source while the reader thread is inside source->next().
struct ThreadedImageSource::State {
    State(std::unique_ptr<ImageSource> src, const ThreadedSourceOptions& options)
        : source(readerSource(std::move(src), options)),
          calib(source->calib()),
          frame_count(source->frameCount()),
          live(source->isLive()),
          drop_oldest(dropsWhenFull(options, *source)),
          ground_truth(source->groundTruth()),
          description("threaded (queue of " + std::to_string(options.queue_capacity) +
                      (drop_oldest ? ", dropping the oldest frame when full" : ", lossless") + ") " +
                      source->description()),
          queue(std::size_t(options.queue_capacity), drop_oldest) {}

    void readerLoop();

    std::unique_ptr<ImageSource> source;
    const RGBDCalib calib;
    const int frame_count;
    const bool live;
    const bool drop_oldest;
    const std::vector<TimedPose> ground_truth;
    const std::string description;
    BoundedFrameQueue queue;
    bool ended = false;  // consumer side only
    std::thread reader;  // started last, joined first
};

void ThreadedImageSource::State::readerLoop() {
    for (;;) {
        QueuedFrame entry;
        bool fatal = false;
        try {
            if (source->next(entry.frame)) {
                entry.kind = QueuedFrame::Kind::Frame;
            } else {
                entry.kind = QueuedFrame::Kind::End;
            }
        } catch (const IoError&) {
            // A bad frame: the source has moved past it (ImageSource::next's contract).
            entry = QueuedFrame{QueuedFrame::Kind::Error, RGBDFrame{}, std::current_exception()};
        } catch (...) {
            // Anything else leaves the source in an unknown state: report it, then end.
            entry = QueuedFrame{QueuedFrame::Kind::Error, RGBDFrame{}, std::current_exception()};
            fatal = true;
        }
        const bool end = entry.kind == QueuedFrame::Kind::End;
        if (!queue.push(std::move(entry))) return;  // closed: nobody is reading any more
        if (fatal) {
            queue.push(QueuedFrame{});
            return;
        }
        if (end) return;
    }
}

ThreadedImageSource::ThreadedImageSource(std::unique_ptr<ImageSource> source, const ThreadedSourceOptions& options) {
    if (options.queue_capacity < 1)
        throw ConfigError("ThreadedImageSource: queue_capacity must be at least 1, got " +
                          std::to_string(options.queue_capacity));
    state_ = std::make_unique<State>(std::move(source), options);
    State* state = state_.get();
    state_->reader = std::thread([state] { state->readerLoop(); });
}

ThreadedImageSource::~ThreadedImageSource() {
    state_->queue.close();
    if (state_->reader.joinable()) state_->reader.join();
}

const RGBDCalib& ThreadedImageSource::calib() const { return state_->calib; }

bool ThreadedImageSource::next(RGBDFrame& frame) {
    if (state_->ended) return false;
    QueuedFrame entry = state_->queue.pop();
    switch (entry.kind) {
        case QueuedFrame::Kind::Frame:
            frame = std::move(entry.frame);
            return true;
        case QueuedFrame::Kind::Error:
            std::rethrow_exception(entry.error);
        case QueuedFrame::Kind::End:
            break;
    }
    state_->ended = true;
    return false;
}

bool ThreadedImageSource::waitForFrame(std::chrono::milliseconds timeout) {
    return state_->ended || state_->queue.waitForEntry(timeout);
}

int ThreadedImageSource::frameCount() const { return state_->frame_count; }
std::string ThreadedImageSource::description() const { return state_->description; }
const std::vector<TimedPose>& ThreadedImageSource::groundTruth() const { return state_->ground_truth; }
bool ThreadedImageSource::isLive() const { return state_->live; }
long ThreadedImageSource::droppedFrames() const { return state_->queue.dropped(); }

}  // namespace voxfuse
