#pragma once
// Turns a hang into a failure: aborts the test program, naming the test, when the scope it guards
// has not ended after a deadline. For tests of threads and devices, where a bug shows as a hang.

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>

namespace voxfuse {
namespace test {

class Watchdog {
public:
    Watchdog(std::chrono::seconds deadline, std::string what) : what_(std::move(what)) {
        thread_ = std::thread([this, deadline] {
            std::unique_lock<std::mutex> lock(mutex_);
            if (!done_cv_.wait_for(lock, deadline, [this] { return done_; })) {
                std::fprintf(stderr, "Watchdog: '%s' still running after %lld s: aborting (a hang)\n", what_.c_str(),
                             static_cast<long long>(deadline.count()));
                std::abort();
            }
        });
    }
    ~Watchdog() {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            done_ = true;
        }
        done_cv_.notify_all();
        thread_.join();
    }
    Watchdog(const Watchdog&) = delete;
    Watchdog& operator=(const Watchdog&) = delete;

private:
    std::string what_;
    std::mutex mutex_;
    std::condition_variable done_cv_;
    bool done_ = false;
    std::thread thread_;
};

}  // namespace test
}  // namespace voxfuse
