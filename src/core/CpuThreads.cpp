// The CPU's worker threads (voxfuse/core/CpuThreads.h): one pool per process, started at the first
// loop and resized when the thread count changes.
//
// A loop ("job") is published by bumping a generation counter; workers that see it register as busy,
// check that the job is still open, and claim tasks from a shared counter until none is left. The
// caller claims tasks too, then closes the job and waits until no worker is busy, so a job's function
// and context are never read after the caller returned. Idle workers spin on the generation for a
// short while and then sleep on a condition variable; a caller only takes the sleep mutex to wake
// workers that said they sleep.

#include "voxfuse/core/CpuThreads.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#endif

#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace {

using cpu_threads_detail::TaskFunction;

constexpr int kMostThreads = 4096;

inline void cpuRelax() {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    __asm__ __volatile__("yield");
#endif
}

// True on this thread while it runs a task (workers: always): a loop started there runs inline.
thread_local bool t_in_task = false;

class Pool {
public:
    Pool(int threads, std::chrono::microseconds spin) : requested_(threads), threads_(threads), spin_(spin) {
        workers_.reserve(std::size_t(threads - 1));
        try {
            for (int k = 1; k < threads; ++k) workers_.emplace_back([this] { work(); });
        } catch (const std::system_error& e) {
            // The system refused a thread (a pids, process or memory limit). Leaving the constructor now
            // would destroy the condition variable the started workers sleep on (a hang in
            // pthread_cond_destroy): the pool runs with the threads it got instead, and says so.
            threads_ = int(workers_.size()) + 1;
            std::fprintf(stderr, "voxfuse: warning: only %d of %d CPU threads could be started (%s); running with %d\n",
                         threads_, threads, e.what(), threads_);
        }
    }

    ~Pool() {
        stop_.store(true);
        generation_.fetch_add(1);
        wakeSleepers();
        for (std::thread& w : workers_) w.join();
    }

    Pool(const Pool&) = delete;
    Pool& operator=(const Pool&) = delete;

    int threads() const { return threads_; }
    int requested() const { return requested_; }  // the count it was made for (threads() may be fewer)

    // One job; only one caller at a time (the caller holds the process's run mutex).
    void run(int tasks, TaskFunction function, const void* context) {
        // No worker is busy here (the last job waited for them), so the job's fields are free to write.
        function_ = function;
        context_ = context;
        tasks_ = tasks;
        next_.store(0, std::memory_order_relaxed);
        closed_.store(false);  // seq_cst: ordered after the fields for a worker that reads it as open
        generation_.fetch_add(1);
        wakeSleepers();
        for (int t = next_.fetch_add(1, std::memory_order_relaxed); t < tasks;
             t = next_.fetch_add(1, std::memory_order_relaxed))
            function(context, t);
        // Every task is claimed; those still running belong to busy workers.
        closed_.store(true);
        for (int spins = 0; busy_.load() != 0;) {
            if (spins < 4096) {
                cpuRelax();
                ++spins;
            } else {
                std::this_thread::yield();  // a worker was preempted mid-task: give it the core
            }
        }
    }

private:
    void wakeSleepers() {
        // A worker counts itself a sleeper before it checks the generation (both seq_cst), so either it
        // sees the new generation or this sees it counted; the mutex orders the notify after its wait.
        if (sleepers_.load() == 0) return;
        { const std::lock_guard<std::mutex> lock(sleep_mutex_); }
        wake_.notify_all();
    }

    // Waits until the generation differs from `seen` or the pool stops: spins for spin_, then sleeps.
    unsigned awaitJob(unsigned seen) {
        const auto spin_end = std::chrono::steady_clock::now() + spin_;
        for (int spins = 1;; ++spins) {
            const unsigned g = generation_.load(std::memory_order_acquire);
            if (g != seen || stop_.load(std::memory_order_relaxed)) return g;
            cpuRelax();
            if (spins % 256 == 0 && std::chrono::steady_clock::now() >= spin_end) break;
        }
        std::unique_lock<std::mutex> lock(sleep_mutex_);
        sleepers_.fetch_add(1);
        wake_.wait(lock, [&] { return generation_.load() != seen || stop_.load(); });
        sleepers_.fetch_sub(1);
        return generation_.load(std::memory_order_acquire);
    }

    void work() {
        t_in_task = true;
        // From the generation the pool was made with, so that a worker that starts late still sees the
        // first job (and a pool that was told to stop before this ran, since stop_ ends every wait).
        unsigned seen = 0;
        for (;;) {
            seen = awaitJob(seen);
            if (stop_.load()) return;
            // Busy before the open check (both seq_cst): either the caller sees this worker busy and
            // waits for it, or this worker sees the job closed and leaves its fields alone.
            busy_.fetch_add(1);
            if (!closed_.load()) {
                const TaskFunction function = function_;
                const void* const context = context_;
                const int tasks = tasks_;
                for (int t = next_.fetch_add(1, std::memory_order_relaxed); t < tasks;
                     t = next_.fetch_add(1, std::memory_order_relaxed))
                    function(context, t);
            }
            busy_.fetch_sub(1);
        }
    }

    const int requested_;
    int threads_;  // those running: fewer than asked for when the system refused some
    const std::chrono::microseconds spin_;
    std::vector<std::thread> workers_;

    TaskFunction function_ = nullptr;
    const void* context_ = nullptr;
    int tasks_ = 0;
    std::atomic<int> next_{0};
    std::atomic<bool> closed_{true};
    std::atomic<int> busy_{0};
    std::atomic<unsigned> generation_{0};
    std::atomic<bool> stop_{false};

    std::atomic<int> sleepers_{0};
    std::mutex sleep_mutex_;
    std::condition_variable wake_;
};

// The whole number in the environment variable `name`, from `least` to `most`, or -1 when it is unset;
// a value that is not one is reported (once: the state that reads it is made once) and ignored. With
// `list`, the first of a comma-separated list, as OMP_NUM_THREADS allows.
long numberFromEnvironment(const char* name, long least, long most, const char* what, bool list = false) {
    const char* text = std::getenv(name);
    if (text == nullptr || *text == '\0') return -1;
    char* end = nullptr;
    const long value = std::strtol(text, &end, 10);
    if (end != text && (*end == '\0' || (list && *end == ',')) && value >= least && value <= most) return value;
    std::fprintf(stderr, "voxfuse: ignoring %s=\"%s\": not %s from %ld to %ld\n", name, text, what, least, most);
    return -1;
}

int defaultThreadCount() {
    for (const char* name : {"VOXFUSE_NUM_THREADS", "OMP_NUM_THREADS"})
        if (const long n = numberFromEnvironment(name, 1, kMostThreads, "a thread count", true); n > 0) return int(n);
#if defined(__linux__)
    cpu_set_t allowed;
    if (sched_getaffinity(0, sizeof(allowed), &allowed) == 0 && CPU_COUNT(&allowed) > 0) return CPU_COUNT(&allowed);
#endif
    return std::max(1u, std::thread::hardware_concurrency());
}

// How long idle workers spin before they sleep: 50 us unless VOXFUSE_SPIN_US says otherwise. The next
// loop of a frame mostly follows within that; see docs/DESIGN_NOTES.md, "CPU threads that sleep".
std::chrono::microseconds spinTime() {
    const long us = numberFromEnvironment("VOXFUSE_SPIN_US", 0, 1000000, "a number of microseconds");
    return std::chrono::microseconds(us >= 0 ? us : 50);
}

struct Threads {
    std::mutex run_mutex;  // one job at a time; held while a job runs and while the pool is replaced
    std::unique_ptr<Pool> pool;
    std::atomic<int> requested{0};  // setCpuThreadCount's count, 0: the default
    int default_count = defaultThreadCount();
    std::chrono::microseconds spin = spinTime();
};

// Never destroyed: workers may still be waiting when static destructors run, and a loop may run from
// a destructor. The child of a fork has none of the parent's workers, so it starts a fresh state.
Threads* g_threads = nullptr;
std::once_flag g_threads_once;

Threads& threads() {
    std::call_once(g_threads_once, [] {
        g_threads = new Threads();
#if defined(__linux__)
        pthread_atfork(nullptr, nullptr, [] {
            Threads* const parent = g_threads;  // its workers are the parent's; leaked on purpose
            g_threads = new Threads();
            g_threads->requested.store(parent->requested.load());
        });
#endif
    });
    return *g_threads;
}

}  // namespace

int cpuThreadCount() {
    Threads& t = threads();
    const int requested = t.requested.load(std::memory_order_relaxed);
    return requested > 0 ? requested : t.default_count;
}

void setCpuThreadCount(int count) {
    if (count < 0 || count > kMostThreads)
        throw ConfigError("setCpuThreadCount: " + std::to_string(count) + " is not a thread count from 1 to " +
                          std::to_string(kMostThreads) + " (or 0, the default)");
    threads().requested.store(count, std::memory_order_relaxed);
}

namespace cpu_threads_detail {

void runTasks(int tasks, TaskFunction function, const void* context) {
    if (tasks <= 0) return;
    const auto run_inline = [&] {
        for (int t = 0; t < tasks; ++t) function(context, t);
    };
    if (tasks == 1 || t_in_task) return run_inline();
    const int count = cpuThreadCount();
    if (count == 1) return run_inline();
    Threads& t = threads();
    std::unique_lock<std::mutex> lock(t.run_mutex, std::try_to_lock);
    if (!lock.owns_lock()) return run_inline();  // another thread's loop holds the workers
    if (!t.pool || t.pool->requested() != count) {
        t.pool.reset();
        t.pool = std::make_unique<Pool>(count, t.spin);
    }
    t_in_task = true;
    t.pool->run(tasks, function, context);
    t_in_task = false;
}

}  // namespace cpu_threads_detail
}  // namespace voxfuse
