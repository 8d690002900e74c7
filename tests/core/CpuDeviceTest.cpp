// The CPU launcher, primitives and atomics (core/CpuDevice.h, core/Atomics.h); their CUDA twins pass
// the same checks in tests/cuda/CudaDeviceTest.cu.

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "DevicePrimitiveChecks.h"
#include "core/CpuDevice.h"
#include "core/EnvironmentSwitch.h"
#include "voxfuse/core/CpuThreads.h"

namespace voxfuse {
namespace {

TEST(CpuDeviceTest, ParallelForVisitsEveryElementOnce) { test::checkParallelForVisitsEveryElementOnce<CpuDevice>(); }
TEST(CpuDeviceTest, AtomicsCombineExactly) { test::checkAtomicsCombineExactly<CpuDevice>(); }
TEST(CpuDeviceTest, CompareAndSwapClaimsOncePerSlot) { test::checkCompareAndSwapClaimsOncePerSlot<CpuDevice>(); }
TEST(CpuDeviceTest, ExclusiveScan) { test::checkExclusiveScan<CpuDevice>(); }
TEST(CpuDeviceTest, SelectIndicesKeepsOrder) { test::checkSelectIndices<CpuDevice>(); }
TEST(CpuDeviceTest, SortUnique) { test::checkSortUnique<CpuDevice>(); }
TEST(CpuDeviceTest, CountMaxAndNormalEquations) { test::checkCountMaxAndNormalEquations<CpuDevice>(); }
// The tracker's poses must not depend on how many cores ran it: the same bits with 1, 2 and 3 threads.
TEST(CpuDeviceTest, NormalEquationsDoNotDependOnTheThreadCount) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    std::vector<float> values(307200);
    for (float& v : values) v = u(rng);
    DeviceScratch scratch(Device::CPU);
    std::vector<NormalEquations<double>> sums;
    for (int threads : {1, 2, 3}) {
        setCpuThreadCount(threads);
        sums.push_back(CpuDevice::sumNormalEquations(int(values.size()), test::PolynomialTerms{values.data()},
                                                     RobustKernel::Huber, 0.2f, scratch));
    }
    setCpuThreadCount(0);
    for (std::size_t t = 1; t < sums.size(); ++t) {
        EXPECT_EQ(sums[t].count, sums[0].count);
        for (int k = 0; k < 21; ++k)
            EXPECT_EQ(sums[t].hessian[k], sums[0].hessian[k]) << "entry " << k << ", run " << t;
        for (int k = 0; k < 6; ++k)
            EXPECT_EQ(sums[t].gradient[k], sums[0].gradient[k]) << "entry " << k << ", run " << t;
        EXPECT_EQ(sums[t].weighted_cost, sums[0].weighted_cost);
    }
}
TEST(CpuDeviceTest, ReadAndWriteOneElement) { test::checkReadAndWrite<CpuDevice>(); }

// A team's shared memory starts unwritten (poisoned), as on the GPU, never zeroed: an item reads the
// poison, or what an earlier item of the same task left, and nothing else.
struct TeamScratch {
    int values[64];
    float weights[8];
};
struct RecordWhatTheTeamFinds {
    int* found;
    void operator()(Team team, int item, TeamScratch& shared) const {
        if (team.rank == 0) found[item] = shared.values[63];
        shared.values[63] = 1000 + item;
    }
};
TEST(CpuDeviceTest, TeamSharedMemoryStartsPoisoned) {
    int poison;
    std::memset(&poison, cpu_detail::kUnwrittenSharedByte, sizeof poison);
    ASSERT_NE(poison, 0);
    const int n = 5000;
    std::vector<int> found(n, 0);
    CpuDevice::parallelForTeams<TeamScratch>(n, RecordWhatTheTeamFinds{found.data()});
    int poisoned = 0;
    for (int i = 0; i < n; ++i) {
        const int f = found[std::size_t(i)];
        poisoned += f == poison;
        ASSERT_TRUE(f == poison || (f >= 1000 && f < 1000 + n)) << "item " << i << " found " << f;
    }
    EXPECT_GE(poisoned, 1) << "every task's first item finds the poison";
}

TEST(EnvironmentSwitchTest, OnlyZeroAndOneAreValues) {
    std::string reported;
    auto report = [&](const std::string& m) { reported = m; };
    EXPECT_FALSE(switchFromText("VOXFUSE_CUDA_SYNC", nullptr, report));
    EXPECT_FALSE(switchFromText("VOXFUSE_CUDA_SYNC", "", report));
    EXPECT_FALSE(switchFromText("VOXFUSE_CUDA_SYNC", "0", report));
    EXPECT_TRUE(switchFromText("VOXFUSE_CUDA_SYNC", "1", report));
    EXPECT_TRUE(reported.empty());
    for (const char* garbage : {"yes", "2", "1 ", "\xff", "on"}) {
        reported.clear();
        EXPECT_FALSE(switchFromText("VOXFUSE_CUDA_SYNC", garbage, report)) << garbage;
        EXPECT_NE(reported.find("VOXFUSE_CUDA_SYNC=\"" + std::string(garbage) + "\""), std::string::npos) << reported;
    }
}

}  // namespace
}  // namespace voxfuse
