// The CPU threads (voxfuse/core/CpuThreads.h): every task runs once, loops nest and overlap from
// several threads without waiting on each other, the count can change between loops, and a forked
// child runs loops on threads of its own.

#include "voxfuse/core/CpuThreads.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <mutex>
#include <thread>
#include <vector>

#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace {

// Restores the default count when a test ends, whatever it set.
struct DefaultThreadCountAfter {
    ~DefaultThreadCountAfter() { setCpuThreadCount(0); }
};

// Waits up to a minute for a forked child: it must exit with status 0; one still running then is
// killed and the test fails with `if_hung`.
void expectChildExitsWithZero(pid_t child, const char* if_hung) {
    int status = 0;
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    pid_t done = 0;
    while ((done = waitpid(child, &status, WNOHANG)) == 0 && std::chrono::steady_clock::now() < give_up)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    if (done == 0) {
        kill(child, SIGKILL);
        waitpid(child, &status, 0);
        FAIL() << if_hung;
    }
    ASSERT_TRUE(WIFEXITED(status)) << "the child died of signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
    EXPECT_EQ(WEXITSTATUS(status), 0);
}

TEST(CpuThreads, TheCountFollowsTheSetting) {
    DefaultThreadCountAfter restore;
    EXPECT_GE(cpuThreadCount(), 1);
    setCpuThreadCount(3);
    EXPECT_EQ(cpuThreadCount(), 3);
    EXPECT_THROW(setCpuThreadCount(-2), ConfigError);
    EXPECT_THROW(setCpuThreadCount(5000), ConfigError);
    EXPECT_EQ(cpuThreadCount(), 3);  // unchanged by the refused counts
    setCpuThreadCount(0);
    EXPECT_GE(cpuThreadCount(), 1);
}

// Thousands of short loops of varied sizes, on counts that change between them: a lost wake-up hangs
// the test, a task run twice or never shows in the counts.
TEST(CpuThreads, EveryTaskRunsExactlyOnceInEveryLoop) {
    DefaultThreadCountAfter restore;
    std::vector<std::atomic<int>> runs(257);
    for (int threads : {2, 3, 8, 1, 4}) {
        setCpuThreadCount(threads);
        for (int loop = 0; loop < 2000; ++loop) {
            const int tasks = loop % int(runs.size());
            for (int t = 0; t < tasks; ++t) runs[std::size_t(t)] = 0;
            forEachCpuTask(tasks, [&](int t) { runs[std::size_t(t)].fetch_add(1); });
            for (int t = 0; t < tasks; ++t)
                ASSERT_EQ(runs[std::size_t(t)].load(), 1)
                    << "task " << t << " of " << tasks << ", " << threads << " threads";
        }
    }
}

// Loops a few milliseconds apart, so that the workers fall asleep between them and must be woken.
TEST(CpuThreads, WorkersThatSleptAreWokenForTheNextLoop) {
    DefaultThreadCountAfter restore;
    setCpuThreadCount(4);
    for (int loop = 0; loop < 20; ++loop) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        std::atomic<int> sum{0};
        forEachCpuTask(100, [&](int t) { sum += t; });
        ASSERT_EQ(sum.load(), 4950);
    }
}

// Two tasks that each wait for the other to start can only finish on two threads at once.
TEST(CpuThreads, TasksRunOnSeveralThreadsAtOnce) {
    DefaultThreadCountAfter restore;
    setCpuThreadCount(2);
    std::atomic<int> started{0};
    std::atomic<bool> met{true};
    forEachCpuTask(2, [&](int) {
        started.fetch_add(1);
        const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
        while (started.load() < 2)
            if (std::chrono::steady_clock::now() > give_up) {
                met = false;
                return;
            }
    });
    EXPECT_TRUE(met.load());
}

TEST(CpuThreads, ALoopInsideATaskRunsOnItsThread) {
    DefaultThreadCountAfter restore;
    setCpuThreadCount(3);
    std::vector<std::atomic<int>> cells(40 * 30);
    forEachCpuTask(40, [&](int row) {
        const std::thread::id outer = std::this_thread::get_id();
        forEachCpuTask(30, [&](int col) {
            EXPECT_EQ(std::this_thread::get_id(), outer);
            cells[std::size_t(row * 30 + col)].fetch_add(1);
        });
    });
    for (const auto& c : cells) ASSERT_EQ(c.load(), 1);
}

// Loops started from several threads at once all finish with every task run once.
TEST(CpuThreads, LoopsFromSeveralThreadsAtOnceAllFinish) {
    DefaultThreadCountAfter restore;
    setCpuThreadCount(3);
    std::vector<std::thread> callers;
    std::atomic<int> wrong{0};
    for (int c = 0; c < 4; ++c)
        callers.emplace_back([&, c] {
            for (int loop = 0; loop < 300; ++loop) {
                std::vector<std::atomic<int>> runs(64 + c);
                forEachCpuTask(int(runs.size()), [&](int t) { runs[std::size_t(t)].fetch_add(1); });
                for (const auto& r : runs) wrong += r.load() == 1 ? 0 : 1;
            }
        });
    for (std::thread& t : callers) t.join();
    EXPECT_EQ(wrong.load(), 0);
}

TEST(CpuThreads, ShareRangesCoverTheRangeOnce) {
    DefaultThreadCountAfter restore;
    setCpuThreadCount(3);
    for (std::size_t n : {std::size_t(0), std::size_t(1), std::size_t(5), std::size_t(4095), std::size_t(100000)}) {
        std::mutex m;
        std::vector<std::pair<std::size_t, std::size_t>> ranges;
        forEachCpuShare(n, 1000, [&](std::size_t begin, std::size_t end) {
            const std::lock_guard<std::mutex> lock(m);
            ranges.emplace_back(begin, end);
        });
        std::sort(ranges.begin(), ranges.end());
        std::size_t covered = 0;
        for (const auto& [begin, end] : ranges) {
            EXPECT_EQ(begin, covered);
            EXPECT_LE(end - begin, std::max<std::size_t>(n, 1));
            covered = end;
        }
        EXPECT_EQ(covered, n);
        EXPECT_LE(ranges.size(), std::max<std::size_t>(1, n / 1000));
    }
}

// The child of a fork has only the thread that forked: its loops must not wait for the parent's workers.
TEST(CpuThreads, AForkedChildRunsLoopsOfItsOwn) {
    DefaultThreadCountAfter restore;
    setCpuThreadCount(3);
    std::atomic<int> sum{0};
    forEachCpuTask(10, [&](int t) { sum += t; });  // the parent's workers exist
    ASSERT_EQ(sum.load(), 45);
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        std::atomic<int> child_sum{0};
        forEachCpuTask(1000, [&](int t) { child_sum += t; });
        if (cpuThreadCount() != 3) _exit(2);  // the count set before the fork holds
        _exit(child_sum.load() == 499500 ? 0 : 1);
    }
    expectChildExitsWithZero(child, "the child's loop hung");
}

// When the system refuses some of the threads (a pids or memory limit), loops run on those that
// started: leaving the pool's constructor with workers asleep on its condition variable hung the
// process in pthread_cond_destroy. Run in a child whose address space leaves room for a few stacks.
TEST(CpuThreads, ThreadsTheSystemRefusesAreDoneWithout) {
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "an address-space limit and AddressSanitizer's shadow memory do not mix";
#else
    DefaultThreadCountAfter restore;
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        long pages = 0;
        if (FILE* statm = std::fopen("/proc/self/statm", "r")) {
            if (std::fscanf(statm, "%ld", &pages) != 1) pages = 0;
            std::fclose(statm);
        }
        if (pages <= 0) _exit(3);
        // Room for about eight 8 MiB thread stacks beyond what the process has mapped.
        const rlim_t limit = rlim_t(pages) * rlim_t(sysconf(_SC_PAGESIZE)) + (rlim_t(64) << 20);
        const struct rlimit as { limit, limit };
        if (setrlimit(RLIMIT_AS, &as) != 0) _exit(4);
        setCpuThreadCount(200);
        std::atomic<int> child_sum{0};
        forEachCpuTask(1000, [&](int t) { child_sum += t; });
        forEachCpuTask(1000, [&](int t) { child_sum += t; });  // the reduced pool is kept, not made again
        _exit(child_sum.load() == 2 * 499500 ? 0 : 1);
    }
    expectChildExitsWithZero(child, "the loop hung when threads were refused");
#endif
}

}  // namespace
}  // namespace voxfuse
