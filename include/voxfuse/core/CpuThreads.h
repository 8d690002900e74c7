#pragma once
// The CPU's worker threads: every parallel loop of the library's CPU layer runs on them.
//
// A loop runs on the calling thread and cpuThreadCount() - 1 workers. After a loop the workers spin
// for a few tens of microseconds, because the next loop of a frame usually follows within that, and
// then sleep: a machine busy with other work gets its cores back between frames and between stages,
// where OpenMP's default policy spins for milliseconds at every barrier.
//
// The count is, in order: setCpuThreadCount(n) with n > 0, the environment's VOXFUSE_NUM_THREADS,
// OMP_NUM_THREADS (its first number), or the CPUs this process may run on. VOXFUSE_SPIN_US sets how
// long idle workers spin (default 50; 0 sleeps at once). Both are read once, when the
// threads are first used.
//
// A loop started from inside another loop, or from a second thread while one runs, runs on its
// calling thread alone. Every loop of the library gives the same result for any number of threads.

#include <algorithm>
#include <cstddef>

namespace voxfuse {

// How many threads a CPU loop runs on (at least 1).
int cpuThreadCount();

// Sets that count for the whole process, from 1 to 4096; 0 returns to the default above. Takes effect
// at the next loop. Throws ConfigError for any other number.
void setCpuThreadCount(int threads);

namespace cpu_threads_detail {
using TaskFunction = void (*)(const void* context, int task);
void runTasks(int tasks, TaskFunction function, const void* context);
}  // namespace cpu_threads_detail

// task(t) for t in [0, tasks), in any order and on any of the threads; returns when all have run.
// Tasks are handed out one at a time to whichever thread is free. A task must not throw: an exception
// that leaves one ends the process (std::terminate), as in an OpenMP loop.
template <class Task>
void forEachCpuTask(int tasks, const Task& task) {
    cpu_threads_detail::runTasks(
        tasks, [](const void* context, int t) noexcept { (*static_cast<const Task*>(context))(t); }, &task);
}

// range(begin, end) over [0, n) in consecutive shares of at least `min_share` elements, four per thread
// at most, on the CPU threads.
template <class Range>
void forEachCpuShare(std::size_t n, std::size_t min_share, const Range& range) {
    if (n == 0) return;
    const std::size_t most = std::size_t(4 * cpuThreadCount());
    const int shares = int(std::max<std::size_t>(1, std::min(most, n / std::max<std::size_t>(min_share, 1))));
    forEachCpuTask(shares, [&](int s) {
        range(n * std::size_t(s) / std::size_t(shares), n * std::size_t(s + 1) / std::size_t(shares));
    });
}

}  // namespace voxfuse
