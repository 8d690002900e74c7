// One dispatch rule: every make...Engine(Device) returns that device's layer or throws DeviceError
// naming what is missing; no engine silently runs on the CPU when CUDA was asked for.

#include <gtest/gtest.h>

#include <string>

#include "voxfuse/core/Error.h"
#include "voxfuse/engines/AllocationEngine.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/engines/LowLevelEngine.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/engines/MeshingEngine.h"
#include "voxfuse/engines/RaycastEngine.h"
#include "voxfuse/engines/Tracker.h"
#include "voxfuse/objects/Voxel.h"

namespace voxfuse {
namespace {

template <class F>
std::string deviceErrorOf(F&& f) {
    try {
        f();
    } catch (const DeviceError& e) {
        return e.what();
    } catch (const std::exception& e) {
        return std::string("not a DeviceError: ") + e.what();
    }
    return "no error";
}

TEST(DeviceDispatchTest, ImageProcessingAndTrackersAreTheRequestedDevicesOrAClearError) {
    EXPECT_EQ(makeLowLevelEngine(Device::CPU)->device(), Device::CPU);
    for (TrackerKind kind : {TrackerKind::Icp, TrackerKind::Color, TrackerKind::Ren, TrackerKind::Rgbd}) {
        TrackerSettings s;
        s.kind = kind;
        EXPECT_NE(makeTracker(s, Device::CPU), nullptr);
        if (device_memory::builtWithCuda())
            EXPECT_NE(makeTracker(s, Device::CUDA), nullptr);  // creating the CUDA layers touches no GPU
        else
            EXPECT_NE(deviceErrorOf([&] { makeTracker(s, Device::CUDA); }).find("is not in this VoxFuse build"),
                      std::string::npos);
    }
    if (device_memory::builtWithCuda())
        EXPECT_EQ(makeLowLevelEngine(Device::CUDA)->device(), Device::CUDA);
    else
        EXPECT_NE(
            deviceErrorOf([] { makeLowLevelEngine(Device::CUDA); }).find("the CUDA LowLevelEngine is not in this"),
            std::string::npos);
}

TEST(DeviceDispatchTest, SceneEnginesAreTheRequestedDevicesOrAClearError) {
    EXPECT_NE((makeAllocationEngine<VoxelS, VoxelBlockHash>(Device::CPU)), nullptr);
    EXPECT_NE((makeIntegrationEngine<VoxelSRgb, PlainVoxelArray>(Device::CPU)), nullptr);
    EXPECT_NE((makeRaycastEngine<VoxelF, VoxelBlockHash>(Device::CPU)), nullptr);
    EXPECT_NE((makeMeshingEngine<VoxelSLabel, PlainVoxelArray>(Device::CPU)), nullptr);
    if (device_memory::builtWithCuda()) {
        // The CUDA layers exist in this build; creating them touches no GPU.
        EXPECT_NE((makeAllocationEngine<VoxelS, VoxelBlockHash>(Device::CUDA)), nullptr);
        EXPECT_NE((makeIntegrationEngine<VoxelSRgbLabel, VoxelBlockHash>(Device::CUDA)), nullptr);
        EXPECT_NE((makeRaycastEngine<VoxelFRgb, PlainVoxelArray>(Device::CUDA)), nullptr);
        EXPECT_NE((makeMeshingEngine<VoxelS, VoxelBlockHash>(Device::CUDA)), nullptr);
    } else {
        for (const std::string& error :
             {deviceErrorOf([] { makeAllocationEngine<VoxelS, VoxelBlockHash>(Device::CUDA); }),
              deviceErrorOf([] { makeIntegrationEngine<VoxelS, VoxelBlockHash>(Device::CUDA); }),
              deviceErrorOf([] { makeRaycastEngine<VoxelS, VoxelBlockHash>(Device::CUDA); }),
              deviceErrorOf([] { makeMeshingEngine<VoxelS, PlainVoxelArray>(Device::CUDA); })})
            EXPECT_NE(error.find("is not in this VoxFuse build"), std::string::npos) << error;
    }
}

TEST(DeviceDispatchTest, ACudaPipelineWithoutAGpuIsRefusedUpFront) {
    if (device_memory::cudaAvailable()) GTEST_SKIP() << "a GPU is present: " << device_memory::cudaDescription();
    MainEngineSettings s;
    s.device = Device::CUDA;
    RGBDCalib calib;
    calib.depth = calib.rgb = Intrinsics{64, 48, 52.5f, 52.5f, 31.5f, 23.5f};
    const std::string error = deviceErrorOf([&] { MainEngine::create(s, calib); });
    EXPECT_NE(error.find("CUDA was requested but is not usable"), std::string::npos) << error;
    EXPECT_NE(deviceErrorOf([] {
                  Scene<VoxelS, VoxelBlockHash>(SceneParams(), VoxelBlockHash(VoxelBlockHashSettings(), Device::CUDA),
                                                Device::CUDA);
              }),
              "no error");
}

TEST(DeviceDispatchTest, HostTableOperationsOnAGpuHashAreRefused) {
    if (!device_memory::cudaAvailable()) GTEST_SKIP() << "needs a GPU: " << device_memory::cudaDescription();
    VoxelBlockHash hash(VoxelBlockHashSettings(), Device::CUDA);
    EXPECT_NE(deviceErrorOf([&] { hash.insert({0, 0, 0}); }).find("on the GPU"), std::string::npos);
    EXPECT_NE(deviceErrorOf([&] { hash.entry(0); }).find("copyTo(Device::CPU)"), std::string::npos);
}

}  // namespace
}  // namespace voxfuse
