// What only the GPU runs: the CUDA launcher, the CUB primitives and the atomics in device code
// (core/CudaDevice.cuh, core/Atomics.h), against the same checks the CPU layer passes
// (tests/core/CpuDeviceTest.cpp); the marching-cubes table as device code reads it; device-side
// fills and range copies of MemoryBlock. Skips visibly without a GPU.

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "../core/DevicePrimitiveChecks.h"
#include "core/CudaDevice.cuh"
#include "voxfuse/core/MemoryBlock.h"
#include "voxfuse/shared/MarchingCubes.h"

namespace voxfuse {
namespace {

class CudaDeviceTest : public ::testing::Test {
protected:
    void SetUp() override {
        if (!device_memory::cudaAvailable()) GTEST_SKIP() << "no usable GPU: " << device_memory::cudaDescription();
    }
};

TEST_F(CudaDeviceTest, ParallelForVisitsEveryElementOnce) {
    test::checkParallelForVisitsEveryElementOnce<CudaDevice>();
}
TEST_F(CudaDeviceTest, AtomicsCombineExactly) { test::checkAtomicsCombineExactly<CudaDevice>(); }
TEST_F(CudaDeviceTest, CompareAndSwapClaimsOncePerSlot) { test::checkCompareAndSwapClaimsOncePerSlot<CudaDevice>(); }
TEST_F(CudaDeviceTest, ExclusiveScan) { test::checkExclusiveScan<CudaDevice>(); }
TEST_F(CudaDeviceTest, SelectIndicesKeepsOrder) { test::checkSelectIndices<CudaDevice>(); }
TEST_F(CudaDeviceTest, SortUnique) { test::checkSortUnique<CudaDevice>(); }
TEST_F(CudaDeviceTest, CountMaxAndNormalEquations) { test::checkCountMaxAndNormalEquations<CudaDevice>(); }
TEST_F(CudaDeviceTest, ReadAndWriteOneElement) { test::checkReadAndWrite<CudaDevice>(); }

struct CopyTable {
    MarchingCubesTable* out;
    VF_HOST_DEVICE void operator()(int) const { *out = marchingCubesTable(); }
};

TEST_F(CudaDeviceTest, MarchingCubesTableReadsTheSameInDeviceCode) {
    MemoryBlock<MarchingCubesTable> table(1, true, true);
    CudaDevice::parallelFor(1, CopyTable{table.device()});
    table.updateHost();
    EXPECT_EQ(0, std::memcmp(table.host(), &kMarchingCubesTable, sizeof(MarchingCubesTable)));
}

TEST_F(CudaDeviceTest, MemoryBlockFillsCopiesRangesAndKnowsTheCurrentCopy) {
    struct Odd {  // 6 bytes: the device fill writes elements byte by byte
        std::int16_t a, b, c;
    };
    MemoryBlock<Odd> m(1001, true, true);
    m.fill(Device::CUDA, Odd{1, -2, 3}, 0, 1001);
    EXPECT_FALSE(m.isCurrent(Device::CPU));
    m.updateHost();
    EXPECT_TRUE(m.isCurrent(Device::CPU));
    for (int i = 0; i < 1001; ++i) ASSERT_TRUE(m.host()[i].a == 1 && m.host()[i].b == -2 && m.host()[i].c == 3);
    const Odd values[3] = {{7, 8, 9}, {10, 11, 12}, {13, 14, 15}};
    m.writeRange(Device::CUDA, 500, values, 3);
    EXPECT_FALSE(m.isCurrent(Device::CPU));
    Odd back[5];
    m.readRange(Device::CUDA, 499, back, 5);
    EXPECT_EQ(back[0].a, 1);
    EXPECT_EQ(back[1].a, 7);
    EXPECT_EQ(back[3].c, 15);
    EXPECT_EQ(back[4].b, -2);

    MemoryBlock<Odd> copy(1001, false, true);
    copyAcross(copy, Device::CUDA, m, Device::CUDA);
    MemoryBlock<Odd> host(1001, true, false);
    copyAcross(host, Device::CPU, copy, Device::CUDA);
    EXPECT_EQ(host.host()[502].c, 15);
}

// A device-only block grows in place (virtual memory management): the contents stay at the same
// address after the first growth, and the memory in use follows the elements, not the reservation.
TEST_F(CudaDeviceTest, MemoryBlockGrowsOnTheDeviceInPlace) {
    MemoryBlock<int> m(1000, false, true);
    std::vector<int> first(1000);
    for (int i = 0; i < 1000; ++i) first[std::size_t(i)] = 3 * i + 1;
    m.writeRange(Device::CUDA, 0, first.data(), first.size());
    const std::size_t before = device_memory::bytesInUse();
    if (!m.growDevice(5000, std::size_t(1) << 30))
        GTEST_SKIP() << "this GPU or driver has no virtual memory management";
    const int* base = m.device();
    EXPECT_LT(device_memory::bytesInUse() - before, std::size_t(64) << 20) << "a 4 GiB reservation is not backed whole";
    m.fill(Device::CUDA, -7, 1000, 4000);
    for (std::size_t count : {std::size_t(5001), std::size_t(3) << 20, std::size_t(40) << 20}) {
        ASSERT_TRUE(m.growDevice(count, std::size_t(1) << 30));
        EXPECT_EQ(m.device(), base) << "grown in place to " << count;
        EXPECT_EQ(m.size(), count);
    }
    std::vector<int> back(5000);
    m.readRange(Device::CUDA, 0, back.data(), back.size());
    for (int i = 0; i < 1000; ++i) ASSERT_EQ(back[std::size_t(i)], 3 * i + 1) << i;
    for (int i = 1000; i < 5000; ++i) ASSERT_EQ(back[std::size_t(i)], -7) << i;
    m.fill(Device::CUDA, 5, (std::size_t(40) << 20) - 10, 10);  // the last mapped elements are writable
    int last = 0;
    m.readRange(Device::CUDA, (std::size_t(40) << 20) - 1, &last, 1);
    EXPECT_EQ(last, 5);
    EXPECT_THROW(m.growDevice(10, std::size_t(1) << 30), Error) << "no shrinking";
    m = MemoryBlock<int>();
    EXPECT_EQ(device_memory::bytesInUse(), before - 1000 * sizeof(int)) << "released whole";
}

}  // namespace
}  // namespace voxfuse
