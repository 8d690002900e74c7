// Swapping: blocks that go to the global cache and come back are bit-identical; a run whose active
// voxel array is smaller than its map fuses the same map as a run without swapping when every stored
// copy arrives in the frame that needs it, and tracks alike; no frame moves more blocks than its
// bound; maps larger than the active array save, load and mesh. On each device.

#include <unistd.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <tuple>
#include <vector>

#include "DeviceTestSupport.h"
#include "SyntheticViews.h"
#include "voxfuse/engines/AllocationEngine.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/engines/RaycastEngine.h"
#include "voxfuse/engines/SwappingEngine.h"
#include "voxfuse/objects/GlobalCache.h"
#include "voxfuse/objects/Voxel.h"

namespace fs = std::filesystem;

namespace voxfuse {
namespace {

using Key = std::tuple<int, int, int>;

std::string orbitMapPath(Device device);

class SwappingEngineTest : public ::testing::TestWithParam<Device> {
protected:
    void SetUp() override { VF_SKIP_IF_UNAVAILABLE(device()); }
    void TearDown() override {
        std::error_code ec;
        fs::remove(orbitMapPath(device()), ec);
        fs::remove(orbitMapPath(device()) + ".again", ec);
    }
    Device device() const { return GetParam(); }
};

const synth::SyntheticScene& world() {
    static const synth::SyntheticScene scene = synth::SyntheticScene::boxAndSphere();
    return scene;
}
const Intrinsics kIntr = test::kinectIntrinsics(160, 120);

// A camera swinging around the scene, 60 degrees to either side and back in `frames` steps: blocks
// leave the view at one end and come back.
Mat4f orbitPose(int k, int frames) {
    const float a = 1.0471976f * std::sin(6.2831853f * float(k) / float(frames));
    return test::lookAt({0.3f + 1.1f * std::cos(a), 1.1f * std::sin(a), 0.8f}, {0.3f, 0.f, 0.1f});
}

// Every non-empty block of a host scene, by position.
std::map<Key, std::vector<VoxelSRgb>> blocksOf(const Scene<VoxelSRgb, VoxelBlockHash>& host) {
    std::map<Key, std::vector<VoxelSRgb>> blocks;
    for (int i = 0; i < host.index().entryCount(); ++i) {
        const HashEntry& e = host.index().entry(i);
        if (e.ptr < 0) continue;
        const VoxelSRgb* b = host.voxels().host() + std::size_t(e.ptr) * kBlockVoxelCount;
        blocks[{e.pos.x, e.pos.y, e.pos.z}].assign(b, b + kBlockVoxelCount);
    }
    return blocks;
}

bool sameBlock(const std::vector<VoxelSRgb>& a, const VoxelSRgb* b) {
    for (int v = 0; v < kBlockVoxelCount; ++v)
        if (!test::sameVoxel(a[std::size_t(v)], b[v])) return false;
    return true;
}

TEST_P(SwappingEngineTest, BlocksSwappedOutAndBackInAreBitIdentical) {
    Scene<VoxelSRgb, VoxelBlockHash> scene(test::centimetreSceneParams(),
                                           VoxelBlockHash(VoxelBlockHashSettings(), device()), device());
    auto allocation = makeAllocationEngine<VoxelSRgb, VoxelBlockHash>(device());
    auto integration = makeIntegrationEngine<VoxelSRgb, VoxelBlockHash>(device());
    auto swapping = makeSwappingEngine<VoxelSRgb>(device());
    GlobalCache cache(sizeof(VoxelSRgb) * kBlockVoxelCount);
    const Mat4f here = orbitPose(0, 8);
    const View view = test::renderView(world(), kIntr, here);
    for (int k = 0; k < 3; ++k) {
        allocation->allocate(scene, view, here);
        integration->integrate(scene, view, here);
    }
    const auto original = blocksOf(test::onHost(scene));
    ASSERT_GT(original.size(), 200u);

    // Looking away with no depth: nothing is visible, every block with data goes out.
    View empty = test::renderView(world(), kIntr, here);
    empty.depth.memory().fill(0.f);
    const Mat4f away = test::lookAt({0.3f, 0.f, 3.f}, {0.3f, 0.f, 5.f});
    allocation->allocate(scene, empty, away);
    const int out = swapping->swapOut(scene, cache, 1 << 20);
    EXPECT_GT(out, 200);
    EXPECT_EQ(scene.index().storedBlocks(), out);
    EXPECT_EQ(cache.storedBlocks(), out);
    {
        const auto host = test::onHost(scene);
        std::vector<VoxelSRgb> stored(kBlockVoxelCount);
        int checked = 0;
        for (int i = 0; i < host.index().entryCount(); ++i) {
            const HashEntry& e = host.index().entry(i);
            if (e.ptr != kEntrySwappedOut) continue;
            cache.read(host.index().storedSlots()[i], stored.data());
            ASSERT_TRUE(sameBlock(original.at({e.pos.x, e.pos.y, e.pos.z}), stored.data()))
                << "stored copy of entry " << i;
            ++checked;
        }
        EXPECT_EQ(checked, out);
    }

    // Back to the view: the blocks its depth needs come back, bit-identical, before anything is fused.
    allocation->allocate(scene, view, here);
    const int in = swapping->swapIn(scene, cache, 1 << 20);
    EXPECT_GT(in, 100);
    EXPECT_EQ(scene.index().storedBlocks(), out - in);
    const auto back = test::onHost(scene);
    int compared = 0;
    for (int i = 0; i < back.index().entryCount(); ++i) {
        const HashEntry& e = back.index().entry(i);
        if (e.ptr < 0 || !original.count({e.pos.x, e.pos.y, e.pos.z})) continue;
        ASSERT_EQ(back.index().storedSlots()[i], kNoStoredCopy);
        ASSERT_TRUE(sameBlock(original.at({e.pos.x, e.pos.y, e.pos.z}),
                              back.voxels().host() + std::size_t(e.ptr) * kBlockVoxelCount));
        ++compared;
    }
    EXPECT_GE(compared, in);
}

// Back at a view whose depth has a hole where the map has surface: the hole's blocks are not seen, but
// the raycast reads them (rays near the blocks it does see cross them). Swapping brings the stored ones
// back and keeps them (they are in the raycast's reach), so its raycast is the run's without swapping.
TEST_P(SwappingEngineTest, RaycastsReadTheBlocksInTheirReachThatTheDepthMissed) {
    using TestScene = Scene<VoxelSRgb, VoxelBlockHash>;
    TestScene plain(test::centimetreSceneParams(), VoxelBlockHash(VoxelBlockHashSettings(), device()), device());
    TestScene swapped(test::centimetreSceneParams(), VoxelBlockHash(VoxelBlockHashSettings(), device()), device());
    auto allocation = makeAllocationEngine<VoxelSRgb, VoxelBlockHash>(device());
    auto integration = makeIntegrationEngine<VoxelSRgb, VoxelBlockHash>(device());
    auto swapping = makeSwappingEngine<VoxelSRgb>(device());
    auto raycast = makeRaycastEngine<VoxelSRgb, VoxelBlockHash>(device());
    GlobalCache cache(sizeof(VoxelSRgb) * kBlockVoxelCount);
    const Mat4f here = orbitPose(0, 8);
    const View view = test::renderView(world(), kIntr, here);
    View away_view = test::renderView(world(), kIntr, here), holed = test::renderView(world(), kIntr, here);
    away_view.depth.memory().fill(0.f);
    for (int y = 0; y < kIntr.height; ++y)  // the left half of the image sees nothing
        for (int x = 0; x < kIntr.width / 2; ++x) holed.depth.host()[std::size_t(x + y * kIntr.width)] = 0.f;
    const Mat4f away = test::lookAt({0.3f, 0.f, 3.f}, {0.3f, 0.f, 5.f});

    for (TestScene* scene : {&plain, &swapped}) {
        for (int k = 0; k < 3; ++k) {
            allocation->allocate(*scene, view, here);
            integration->integrate(*scene, view, here);
        }
        allocation->allocate(*scene, away_view, away);  // everything leaves the visible list
    }
    EXPECT_GT(swapping->swapOut(swapped, cache, 1 << 20), 200);

    for (TestScene* scene : {&plain, &swapped}) {
        allocation->allocate(*scene, holed, here);
        if (scene == &swapped) swapping->swapIn(swapped, cache, 1 << 20);
        integration->integrate(*scene, holed, here);
    }
    swapping->swapOut(swapped, cache, 1 << 20);  // blocks in the reach stay
    RenderState from_plain, from_swapped;
    raycast->raycast(plain, kIntr, here, from_plain);
    raycast->raycast(swapped, kIntr, here, from_swapped);
    for (RenderState* r : {&from_plain, &from_swapped}) {
        r->updateHost();
        r->depth_range.memory().updateHost();
    }
    const RenderState& a = from_plain;
    int hole_hits = 0;  // surface found where the depth had none: read from blocks the depth missed
    for (int y = 0; y < kIntr.height; ++y)
        for (int x = 0; x < kIntr.width / 2; ++x) hole_hits += a.points_world.host()[x + y * kIntr.width].w > 0.f;
    EXPECT_GT(hole_hits, 50) << "the raycast reads surface in the hole";
    const test::ChannelDifferences d = test::raycastDifferences(from_plain, from_swapped);
    EXPECT_TRUE(d.none()) << d.describe();
}

// ---- Whole runs through the main engine ----

struct RunResult {
    std::vector<Mat4f> poses;
    std::vector<AllocationStats> stats;
    std::vector<char> map_body;  // the saved map without its header (which names the active array's size)
    std::size_t mesh_triangles = 0;
};

std::vector<char> mapBody(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (bytes.size() < 16) return {};
    std::uint32_t header = 0;
    for (int i = 0; i < 4; ++i) header |= std::uint32_t(std::uint8_t(bytes[12 + std::size_t(i)])) << (8 * i);
    return std::vector<char>(bytes.begin() + 16 + std::ptrdiff_t(header), bytes.end());
}

// Per process: ctest runs the cases of this suite in parallel processes, which must not share files.
std::string tempFile(const std::string& name) {
    return (fs::temp_directory_path() / ("voxfuse_" + std::to_string(::getpid()) + "_" + name)).string();
}
std::string orbitMapPath(Device device) { return tempFile("swap_" + std::string(deviceName(device)) + ".vfm"); }

RunResult runOrbit(Device device, bool tracked, const SwapSettings& swap, int active_blocks, int frames = 40) {
    MainEngineSettings s;
    s.device = device;
    s.voxel_type = VoxelType::SRgb;
    s.scene = test::centimetreSceneParams();
    s.swap = swap;
    if (active_blocks > 0) s.hash.max_block_count = active_blocks;
    s.hash.blocks_per_growth = 256;
    RGBDCalib calib;
    calib.depth = calib.rgb = kIntr;
    calib.disparity = DisparityCalib::affine(0.001f);
    auto engine = MainEngine::create(s, calib);
    RunResult r;
    for (int k = 0; k < frames; ++k) {
        const Mat4f truth = rigidInverse(orbitPose(0, frames)) * orbitPose(k, frames);
        const FrameResult f = engine->processFrame(
            test::toRgbdFrame(test::renderView(world(), kIntr, orbitPose(k, frames)), k), tracked ? nullptr : &truth);
        r.poses.push_back(f.T_world_camera);
        r.stats.push_back(f.allocation);
    }
    const std::string path = orbitMapPath(device);
    engine->saveMap(path);
    r.map_body = mapBody(path);
    Mesh mesh;
    engine->extractMesh(mesh);
    r.mesh_triangles = mesh.triangles.size();
    return r;
}

float ateRmse(const std::vector<Mat4f>& poses, int frames) {
    double sum = 0.0;
    for (int k = 0; k < int(poses.size()); ++k) {
        const Mat4f truth = rigidInverse(orbitPose(0, frames)) * orbitPose(k, frames);
        const Vec3f d = poses[std::size_t(k)].translation() - truth.translation();
        sum += double(dot(d, d));
    }
    return float(std::sqrt(sum / double(poses.size())));
}

TEST_P(SwappingEngineTest, AnActiveArraySmallerThanTheMapFusesTheSameMapWhenNothingWaits) {
    const RunResult plain = runOrbit(device(), false, SwapSettings(), 0);
    int map_blocks = 0;
    for (const AllocationStats& st : plain.stats) map_blocks = std::max(map_blocks, st.blocks_allocated);
    SwapSettings swap;
    swap.enabled = true;
    swap.blocks_per_frame = 1 << 20;
    const int active = map_blocks * 2 / 3;
    const RunResult swapped = runOrbit(device(), false, swap, active);
    int stored = 0;
    for (const AllocationStats& st : swapped.stats) {
        stored = std::max(stored, st.blocks_stored);
        EXPECT_LE(st.blocks_allocated, active);
        EXPECT_EQ(st.allocation_failures_this_frame, 0);
    }
    EXPECT_GT(stored, map_blocks / 4) << "the map did not outgrow the active array";
    ASSERT_FALSE(plain.map_body.empty());
    EXPECT_TRUE(plain.map_body == swapped.map_body) << "the same voxels, bit for bit";
    EXPECT_EQ(plain.mesh_triangles, swapped.mesh_triangles);

    swap.swap_file = tempFile("swap_test.bin");
    const RunResult on_disk = runOrbit(device(), false, swap, active);
    EXPECT_TRUE(plain.map_body == on_disk.map_body) << "a swap file holds the same";
}

// Tracked: with nothing waiting, the swapped run's raycasts read what the run without swapping reads
// (the blocks in their reach stay in the array, or come back to it, even where the depth did not reach
// them), so the poses and the map are the same bit for bit; with 24 blocks per frame copies wait and
// the ATE stays within 0.5 mm.
TEST_P(SwappingEngineTest, TrackedRunsFollowTheRunWithoutSwapping) {
    const int frames = 120;  // at most 3 degrees a frame
    const RunResult plain = runOrbit(device(), true, SwapSettings(), 0, frames);
    EXPECT_LT(ateRmse(plain.poses, frames), 0.01f) << "the run without swapping tracks (1 cm voxels, 160x120)";
    int map_blocks = 0;
    for (const AllocationStats& st : plain.stats) map_blocks = std::max(map_blocks, st.blocks_allocated);

    SwapSettings swap;
    swap.enabled = true;
    swap.blocks_per_frame = 1 << 20;
    const RunResult unbounded = runOrbit(device(), true, swap, map_blocks * 2 / 3, frames);
    ASSERT_EQ(plain.poses.size(), unbounded.poses.size());
    int stored = 0;
    for (const AllocationStats& st : unbounded.stats) stored = std::max(stored, st.blocks_stored);
    EXPECT_GT(stored, map_blocks / 10) << "the map did not outgrow the active array";
    int first_different = -1;
    for (std::size_t k = 0; k < plain.poses.size() && first_different < 0; ++k)
        if (std::memcmp(plain.poses[k].m, unbounded.poses[k].m, sizeof(plain.poses[k].m)) != 0)
            first_different = int(k);
    EXPECT_EQ(first_different, -1) << "the poses are those of the run without swapping, bit for bit";
    EXPECT_TRUE(plain.map_body == unbounded.map_body) << "the same voxels, bit for bit";

    swap.blocks_per_frame = 24;
    const RunResult tight = runOrbit(device(), true, swap, map_blocks * 2 / 3, frames);
    bool waited = false;
    for (const AllocationStats& st : tight.stats) {
        EXPECT_LE(st.blocks_swapped_in_this_frame, 24);
        EXPECT_LE(st.blocks_swapped_out_this_frame, 24);
        waited = waited || st.blocks_activated_this_frame > st.blocks_swapped_in_this_frame;
    }
    EXPECT_TRUE(waited) << "some stored copies waited for a later frame";
    EXPECT_NEAR(ateRmse(tight.poses, frames), ateRmse(plain.poses, frames), 0.0005f)
        << "ATE within 0.5 mm of the run without swapping";
}

TEST_P(SwappingEngineTest, AMapLargerThanTheActiveArrayLoadsAndMeshes) {
    const RunResult plain = runOrbit(device(), false, SwapSettings(), 0, 24);
    const std::string path = orbitMapPath(device());
    const MapFileInfo info = readMapFileInfo(path);
    MainEngineSettings s = settingsForMap(info, MainEngineSettings());
    s.device = device();
    s.swap.enabled = true;
    s.hash.max_block_count = int(info.record_count / 3);  // the map is three times the active array
    RGBDCalib calib;
    calib.depth = calib.rgb = kIntr;
    auto engine = MainEngine::create(s, calib);
    engine->loadMap(path);
    Mesh mesh;
    engine->extractMesh(mesh);
    EXPECT_EQ(mesh.triangles.size(), plain.mesh_triangles);
    const std::string again = path + ".again";
    engine->saveMap(again);
    EXPECT_TRUE(mapBody(again) == plain.map_body);
}

INSTANTIATE_TEST_SUITE_P(Devices, SwappingEngineTest, test::kAllDevices, test::DeviceName());

}  // namespace
}  // namespace voxfuse
