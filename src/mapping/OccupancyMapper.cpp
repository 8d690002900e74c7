// OccupancyMapper on OctoMap: submit() turns a subsampled depth frame into world-frame beam
// endpoints and queues them; one worker thread ray-casts them into an octomap::OcTree.

#include "voxfuse/mapping/OccupancyMapper.h"

#include <octomap/OcTree.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <exception>
#include <fstream>
#include <mutex>
#include <thread>

#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace {

struct QueuedScan {
    octomap::Pointcloud points_world;
    octomap::point3d sensor_origin;
};

const OccupancySettings& validated(const OccupancySettings& s) {
    if (!(s.resolution_m > 0.f))
        throw ConfigError("occupancy: resolution_m must be > 0, got " + std::to_string(s.resolution_m));
    if (s.frame_step < 1) throw ConfigError("occupancy: frame_step must be >= 1, got " + std::to_string(s.frame_step));
    if (s.pixel_step < 1) throw ConfigError("occupancy: pixel_step must be >= 1, got " + std::to_string(s.pixel_step));
    if (s.queue_capacity < 1)
        throw ConfigError("occupancy: queue_capacity must be >= 1, got " + std::to_string(s.queue_capacity));
    return s;
}

// Every pixel_step-th pixel in x and y (Algorithm 5's spatial downsampling), unprojected and moved to the world frame.
QueuedScan subsampledScan(const Image<float>& depth_m, const Intrinsics& intrinsics, const Mat4f& T_world_camera,
                          int pixel_step) {
    QueuedScan scan;
    const Vec3f origin = T_world_camera.translation();
    scan.sensor_origin = octomap::point3d(origin.x, origin.y, origin.z);
    const int columns = (depth_m.width() + pixel_step - 1) / pixel_step;
    const int rows = (depth_m.height() + pixel_step - 1) / pixel_step;
    scan.points_world.reserve(std::size_t(columns) * std::size_t(rows));
    for (int y = 0; y < depth_m.height(); y += pixel_step)
        for (int x = 0; x < depth_m.width(); x += pixel_step) {
            const float d = depth_m.at(x, y);
            if (!(d > 0.f) || !std::isfinite(d)) continue;
            const Vec3f p = transformPoint(T_world_camera, intrinsics.unproject(float(x), float(y), d));
            scan.points_world.push_back(p.x, p.y, p.z);
        }
    return scan;
}

}  // namespace

struct OccupancyMapper::Impl {
    explicit Impl(const OccupancySettings& s) : settings(validated(s)), tree(s.resolution_m) {}
    void runWorker();

    const OccupancySettings settings;

    mutable std::mutex tree_mutex;  // the worker inserts while occupancyAt() reads
    octomap::OcTree tree;

    mutable std::mutex queue_mutex;  // guards everything below
    std::condition_variable queue_changed;
    std::deque<QueuedScan> queue;
    bool finishing = false;   // insert what is queued, then stop
    bool abandoning = false;  // stop after the scan in hand
    OccupancyStats stats;
    std::exception_ptr failure;  // what ended the worker early (OctoMap out of memory), rethrown by finish()

    std::mutex join_mutex;  // finish() may be called from several threads: one joins
    std::thread worker;     // last: started once everything above exists
};

void OccupancyMapper::Impl::runWorker() {
    const double max_range = settings.max_range_m > 0.f ? double(settings.max_range_m) : -1.0;
    for (;;) {
        QueuedScan scan;
        {
            std::unique_lock<std::mutex> lock(queue_mutex);
            queue_changed.wait(lock, [&] { return abandoning || finishing || !queue.empty(); });
            if (abandoning || queue.empty()) return;
            scan = std::move(queue.front());
            queue.pop_front();
        }
        const auto start = std::chrono::steady_clock::now();
        try {
            std::lock_guard<std::mutex> lock(tree_mutex);
            tree.insertPointCloud(scan.points_world, scan.sensor_origin, max_range);
        } catch (...) {
            // An exception leaving a std::thread ends the process: keep it for finish() instead.
            std::lock_guard<std::mutex> lock(queue_mutex);
            failure = std::current_exception();
            return;
        }
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        std::lock_guard<std::mutex> lock(queue_mutex);
        ++stats.frames_inserted;
        stats.points_inserted += std::int64_t(scan.points_world.size());
        stats.insert_ms += ms;
    }
}

OccupancyMapper::OccupancyMapper(const OccupancySettings& settings) : impl_(std::make_unique<Impl>(settings)) {
    impl_->worker = std::thread(&Impl::runWorker, impl_.get());
}

OccupancyMapper::~OccupancyMapper() {
    {
        std::lock_guard<std::mutex> lock(impl_->queue_mutex);
        impl_->abandoning = true;
        impl_->queue.clear();
    }
    impl_->queue_changed.notify_all();
    std::lock_guard<std::mutex> lock(impl_->join_mutex);
    if (impl_->worker.joinable()) impl_->worker.join();
}

bool OccupancyMapper::submit(const Image<float>& depth_m, const Intrinsics& intrinsics, const Mat4f& T_world_camera) {
    if (depth_m.size() != intrinsics.size())
        throw ConfigError("occupancy: depth image " + std::to_string(depth_m.width()) + "x" +
                          std::to_string(depth_m.height()) + " does not match the intrinsics " +
                          std::to_string(intrinsics.width) + "x" + std::to_string(intrinsics.height));
    if (depth_m.pixelCount() > 0 && !depth_m.host()) throw ConfigError("occupancy: the depth image has no host copy");
    Impl& m = *impl_;
    {
        std::lock_guard<std::mutex> lock(m.queue_mutex);
        if (m.finishing) throw Error("OccupancyMapper::submit() after finish()");
        const std::int64_t index = m.stats.frames_submitted++;
        if (index % m.settings.frame_step != 0) {
            ++m.stats.frames_skipped;
            return true;
        }
        // Checked before the copy too, so that a busy worker costs the caller nothing.
        if (m.queue.size() >= std::size_t(m.settings.queue_capacity)) {
            ++m.stats.frames_dropped;
            return false;
        }
    }
    QueuedScan scan = subsampledScan(depth_m, intrinsics, T_world_camera, m.settings.pixel_step);
    {
        std::lock_guard<std::mutex> lock(m.queue_mutex);
        if (m.finishing) throw Error("OccupancyMapper::submit() after finish()");  // finish() raced this call
        if (m.queue.size() >= std::size_t(m.settings.queue_capacity)) {            // another producer got there first
            ++m.stats.frames_dropped;
            return false;
        }
        m.queue.push_back(std::move(scan));
    }
    m.queue_changed.notify_one();
    return true;
}

void OccupancyMapper::finish() {
    {
        std::lock_guard<std::mutex> lock(impl_->queue_mutex);
        impl_->finishing = true;
    }
    impl_->queue_changed.notify_all();
    {
        std::lock_guard<std::mutex> lock(impl_->join_mutex);
        if (impl_->worker.joinable()) impl_->worker.join();
    }
    std::lock_guard<std::mutex> lock(impl_->queue_mutex);
    if (impl_->failure) std::rethrow_exception(impl_->failure);
}

void OccupancyMapper::write(const std::string& path) {
    finish();
    // Opened here rather than by OctoMap, which only prints to stderr when it cannot open the file.
    std::ofstream file(path, std::ios::binary);
    if (!file) throw IoError(path, "cannot open for writing");
    std::lock_guard<std::mutex> lock(impl_->tree_mutex);
    // writeBinary() converts to maximum likelihood and prunes in place: fine, the map is final.
    if (!impl_->tree.writeBinary(file) || !file.flush())
        throw IoError(path, "cannot write the occupancy map (OctoMap .bt)");
}

Occupancy OccupancyMapper::occupancyAt(Vec3f p_world) const {
    std::lock_guard<std::mutex> lock(impl_->tree_mutex);
    const octomap::OcTreeNode* node = impl_->tree.search(double(p_world.x), double(p_world.y), double(p_world.z));
    if (!node) return Occupancy::Unknown;
    return impl_->tree.isNodeOccupied(node) ? Occupancy::Occupied : Occupancy::Free;
}

OccupancyStats OccupancyMapper::stats() const {
    std::lock_guard<std::mutex> lock(impl_->queue_mutex);
    return impl_->stats;
}

const OccupancySettings& OccupancyMapper::settings() const { return impl_->settings; }

}  // namespace voxfuse
