// The CPU launcher, primitives and atomics (core/CpuDevice.h, core/Atomics.h); their CUDA twins pass
// the same checks in tests/cuda/CudaDeviceTest.cu.

#include <gtest/gtest.h>

#include "DevicePrimitiveChecks.h"
#include "core/CpuDevice.h"

namespace voxfuse {
namespace {

TEST(CpuDeviceTest, ParallelForVisitsEveryElementOnce) { test::checkParallelForVisitsEveryElementOnce<CpuDevice>(); }
TEST(CpuDeviceTest, AtomicsCombineExactly) { test::checkAtomicsCombineExactly<CpuDevice>(); }
TEST(CpuDeviceTest, ExclusiveScan) { test::checkExclusiveScan<CpuDevice>(); }
TEST(CpuDeviceTest, SelectIndicesKeepsOrder) { test::checkSelectIndices<CpuDevice>(); }
TEST(CpuDeviceTest, SortUnique) { test::checkSortUnique<CpuDevice>(); }
TEST(CpuDeviceTest, CountMaxAndNormalEquations) { test::checkCountMaxAndNormalEquations<CpuDevice>(); }
TEST(CpuDeviceTest, ReadAndWriteOneElement) { test::checkReadAndWrite<CpuDevice>(); }

}  // namespace
}  // namespace voxfuse
