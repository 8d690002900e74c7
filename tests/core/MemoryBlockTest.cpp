// MemoryBlock: which copy is current, range copies and fills (host side; the device side is checked
// in tests/cuda/CudaDeviceTest.cu), and the errors of misuse.

#include <gtest/gtest.h>

#include "voxfuse/core/Error.h"
#include "voxfuse/core/Image.h"
#include "voxfuse/core/MemoryBlock.h"

namespace voxfuse {
namespace {

TEST(MemoryBlockTest, RangesAndFillsOnTheHost) {
    MemoryBlock<int> m(10, true, false);
    m.fill(-1);
    const int values[3] = {4, 5, 6};
    m.writeRange(Device::CPU, 2, values, 3);
    m.fill(Device::CPU, 9, 8, 2);
    int back[10];
    m.readRange(Device::CPU, 0, back, 10);
    const int expected[10] = {-1, -1, 4, 5, 6, -1, -1, -1, 9, 9};
    for (int i = 0; i < 10; ++i) EXPECT_EQ(back[i], expected[i]) << i;

    MemoryBlock<int> other(10, true, false);
    other.fill(0);
    other.copyRangeFrom(Device::CPU, m, 2, 0, 3);
    EXPECT_EQ(other.host()[0], 4);
    EXPECT_EQ(other.host()[2], 6);
    EXPECT_EQ(other.host()[3], 0);
    MemoryBlock<int> copy(10, true, false);
    copyAcross(copy, Device::CPU, m, Device::CPU);
    EXPECT_EQ(copy.host()[9], 9);
}

// A host block grown within its reserve keeps its data in place; beyond it, the data moves with it.
TEST(MemoryBlockTest, GrowingOnTheHostKeepsTheContents) {
    MemoryBlock<int> m(1000, true, false);  // a plain allocation: the first growth reserves
    for (int i = 0; i < 1000; ++i) m.host()[i] = i;
    m.growHost(2000, 1 << 20);
    ASSERT_EQ(m.size(), 2000u);
    for (int i = 1000; i < 2000; ++i) m.host()[i] = i;
    const int* reserved = m.host();
    m.growHost(1 << 19, 1 << 20);
    EXPECT_EQ(m.host(), reserved) << "within the reserve nothing moves";
    m.fill(Device::CPU, -1, 2000, (1 << 19) - 2000);
    m.growHost((1 << 20) + 5, 1 << 20);  // beyond it
    ASSERT_EQ(m.size(), std::size_t(1 << 20) + 5);
    for (int i = 0; i < 2000; ++i) ASSERT_EQ(m.host()[i], i);
    EXPECT_EQ(m.host()[(1 << 19) - 1], -1);
    EXPECT_THROW(m.growHost(10, 0), Error) << "it does not shrink";

    MemoryBlock<int> moved(std::move(m));
    EXPECT_EQ(moved.host()[1999], 1999);
    MemoryBlock<int> empty;
    empty.growHost(0, 0);  // nothing to hold: no memory
    EXPECT_FALSE(empty.onHost());
    empty.growHost(3, 0);
    empty.fill(7);
    EXPECT_EQ(empty.host()[2], 7);
    moved = std::move(empty);  // frees the grown block
    EXPECT_EQ(moved.size(), 3u);
}

TEST(MemoryBlockTest, RangesOutsideTheBlockOrOnAMissingCopyAreRefused) {
    MemoryBlock<int> m(10, true, false);
    int v[4] = {};
    EXPECT_THROW(m.writeRange(Device::CPU, 8, v, 4), Error);
    EXPECT_THROW(m.readRange(Device::CPU, 11, v, 0), Error);
    EXPECT_THROW(m.readRange(Device::CUDA, 0, v, 1), DeviceError) << "there is no device copy";
    MemoryBlock<int> small(3, true, false);
    EXPECT_THROW(copyAcross(small, Device::CPU, m, Device::CPU), Error) << "sizes differ";
}

TEST(MemoryBlockTest, AHostOnlyBlockIsAlwaysCurrentOnTheHost) {
    MemoryBlock<float> m(4, true, false);
    EXPECT_TRUE(m.isCurrent(Device::CPU));
    EXPECT_FALSE(m.isCurrent(Device::CUDA));
    m.host()[0] = 1.f;
    EXPECT_TRUE(m.isCurrent(Device::CPU));
    m.updateHost();  // nothing to do, nothing thrown
    EXPECT_NO_THROW(m.releaseDevice());
}

TEST(MemoryBlockTest, ReallocationKeepsCopiesThatWereNotAskedForWhenTheSizeMatches) {
    MemoryBlock<int> m(16, true, false, HostMemory::Pinned);
    const int* before = m.host();
    m.allocate(16, true, false);  // pageable asked: pinned (or its fallback) serves
    EXPECT_EQ(m.host(), before);
    m.allocate(17, true, false);
    EXPECT_EQ(m.size(), 17u);
}

// A failed allocation leaves the block empty, not claiming a size without memory behind it: buffers
// grown on demand (size() < needed) then try again instead of handing a null pointer to a kernel.
TEST(MemoryBlockTest, AFailedAllocationLeavesTheBlockEmpty) {
    if (device_memory::cudaAvailable()) GTEST_SKIP() << "needs a device allocation that fails: a machine without a GPU";
    MemoryBlock<int> m(8, true, false);
    EXPECT_THROW(m.allocate(16, true, true), Error);  // the host copy is made, then the device copy fails
    EXPECT_EQ(m.size(), 0u);
    EXPECT_FALSE(m.onHost());
    EXPECT_FALSE(m.onDevice());
    m.allocate(16, true, false);  // and the block is usable again
    EXPECT_EQ(m.size(), 16u);
    EXPECT_TRUE(m.onHost());
}

TEST(MemoryBlockTest, ImagesKeepTheirMemoryAcrossFramesOfOneSize) {
    Image<float> image({64, 48});
    const float* before = image.host();
    image.resize({64, 48});
    EXPECT_EQ(image.host(), before);
}

}  // namespace
}  // namespace voxfuse
