// Allocation for the voxel block hash: every block a depth frame needs is allocated and visible, the
// visible list follows the frustum, full capacities are counted exactly, empty blocks are removed, and
// the table depends on the frames only. Every test runs on each device (DeviceTestSupport.h).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <cmath>
#include <map>
#include <set>
#include <tuple>
#include <vector>

#include "DeviceTestSupport.h"
#include "SyntheticViews.h"
#include "voxfuse/engines/AllocationEngine.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/objects/Voxel.h"
#include "core/CpuDevice.h"
#include "cpu/AllocationShapes_CPU.h"
#include "voxfuse/core/CpuThreads.h"
#include "voxfuse/shared/Allocation.h"
#include "voxfuse/shared/HashAccess.h"

namespace voxfuse {
namespace {

using Key = std::tuple<int, int, int>;
using BlockSet = std::set<Key>;
Key key(Vec3i b) { return {b.x, b.y, b.z}; }
using HashScene = Scene<VoxelS, VoxelBlockHash>;

SceneParams testParams() { return test::centimetreSceneParams(); }

HashScene makeScene(const SceneParams& params, Device device, VoxelBlockHashSettings s = VoxelBlockHashSettings()) {
    return HashScene(params, VoxelBlockHash(s, device), device);
}

const Intrinsics kIntr = test::kinectIntrinsics(160, 120);
const synth::SyntheticScene& world() {
    static const synth::SyntheticScene scene = synth::SyntheticScene::boxAndSphere();
    return scene;
}
Mat4f poseA() { return test::lookAt({1.0f, -0.8f, 0.7f}, {0.3f, 0.f, 0.1f}); }
Mat4f poseB() { return test::lookAt({0.2f, 1.1f, 0.9f}, {0.2f, 0.f, 0.1f}); }

// Brute force, written from integration's own rule and nothing of the allocation code: the blocks of
// every voxel that the frame gives a signed distance below +1, i.e. that projects into a pixel with a
// valid depth d and lies at a depth z in [d - mu, d + mu), and with `neighbours` also of those voxels'
// 26 neighbours (which marching cubes and trilinear reads take with them).
BlockSet blocksTheFrameNeeds(const View& view, const Mat4f& T_world_camera, const SceneParams& params,
                             bool neighbours = true) {
    const Mat4f T_camera_world = rigidInverse(T_world_camera);
    const Intrinsics& in = view.calib.depth;
    BlockSet needed;
    // Every voxel of the box around the frustum slab between the nearest and farthest depth (+- mu).
    float d_min = 1e9f, d_max = 0.f;
    for (std::size_t i = 0; i < view.depth.pixelCount(); ++i) {
        const float d = view.depth.host()[i];
        if (d >= params.view_frustum_min_m && d <= params.view_frustum_max_m)
            d_min = std::min(d_min, d), d_max = std::max(d_max, d);
    }
    Vec3f lo{1e9f, 1e9f, 1e9f}, hi{-1e9f, -1e9f, -1e9f};
    for (int k = 0; k < 8; ++k) {
        const float z = (k & 4) ? d_max + params.mu_m : d_min - params.mu_m;
        const Vec3f corner = transformPoint(
            T_world_camera, in.unproject((k & 1) ? float(in.width) : -1.f, (k & 2) ? float(in.height) : -1.f, z));
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], corner[a]), hi[a] = std::max(hi[a], corner[a]);
    }
    const Vec3i first = floorToInt(lo / params.voxel_size_m) - Vec3i{1, 1, 1},
                last = floorToInt(hi / params.voxel_size_m) + Vec3i{2, 2, 2};
    const float reach = d_max + params.mu_m;
    for (int z = first.z; z <= last.z; ++z)
        for (int y = first.y; y <= last.y; ++y)
            for (int x = first.x; x <= last.x; ++x) {
                const Vec3f p = transformPoint(T_camera_world, toFloat(Vec3i{x, y, z}) * params.voxel_size_m);
                if (p.z < 0.01f || p.z > reach) continue;
                const float u = in.fx * p.x / p.z + in.cx, v = in.fy * p.y / p.z + in.cy;
                if (u < -0.5f || v < -0.5f) continue;
                const int iu = int(u + 0.5f), iv = int(v + 0.5f);
                if (iu >= in.width || iv >= in.height) continue;
                const float d = view.depth.at(iu, iv);
                if (!(d >= params.view_frustum_min_m && d <= params.view_frustum_max_m)) continue;
                const float eta = d - p.z;
                if (!(eta >= -params.mu_m && eta < params.mu_m)) continue;
                const int reach_voxels = neighbours ? 1 : 0;
                for (int dz = -reach_voxels; dz <= reach_voxels; ++dz)
                    for (int dy = -reach_voxels; dy <= reach_voxels; ++dy)
                        for (int dx = -reach_voxels; dx <= reach_voxels; ++dx)
                            needed.insert(key(blockOfVoxel({x + dx, y + dy, z + dz})));
            }
    return needed;
}

BlockSet allocatedBlocks(const VoxelBlockHash& hash) {
    const VoxelBlockHash host = hash.copyTo(Device::CPU);
    BlockSet s;
    for (int i = 0; i < host.entryCount(); ++i)
        if (host.entry(i).ptr >= 0) s.insert({host.entry(i).pos.x, host.entry(i).pos.y, host.entry(i).pos.z});
    return s;
}

BlockSet visibleBlocks(const VoxelBlockHash& hash) {
    const VoxelBlockHash host = hash.copyTo(Device::CPU);
    BlockSet s;
    for (int k = 0; k < host.visibleCount(); ++k) {
        const HashEntry& e = host.entry(host.visibleEntries()[k]);
        s.insert({e.pos.x, e.pos.y, e.pos.z});
    }
    return s;
}

// The blocks stage 1 walks for a frame (the shared per-pixel function, serially), for exact accounting.
BlockSet blocksOnSegments(const View& view, const Mat4f& pose, const SceneParams& params) {
    const DepthSegmentFrame f = makeDepthSegmentFrame(params, view, pose);
    BlockSet s;
    auto collect = [&](Vec3i b) { s.insert(key(b)); };
    for (int y = 0; y < kIntr.height; ++y)
        for (int x = 0; x < kIntr.width; ++x) forEachBlockOnDepthSegment(f, x, y, collect);
    return s;
}

int missingFrom(const BlockSet& needed, const BlockSet& have) {
    int missing = 0;
    for (const Key& k : needed) missing += have.count(k) == 0;
    return missing;
}

class AllocationEngineTest : public ::testing::TestWithParam<Device> {
protected:
    void SetUp() override { VF_SKIP_IF_UNAVAILABLE(GetParam()); }
    Device device() const { return GetParam(); }
};

TEST_P(AllocationEngineTest, EveryBlockTheDepthNeedsIsAllocatedAndVisible) {
    const SceneParams params = testParams();
    HashScene scene = makeScene(params, device());
    auto allocation = makeAllocationEngine<VoxelS, VoxelBlockHash>(device());
    const Mat4f poses[] = {poseA(), poseB()};
    for (const Mat4f& pose : poses) {
        const View view = test::renderView(world(), kIntr, pose, false);
        const AllocationStats stats = allocation->allocate(scene, view, pose);
        const BlockSet needed = blocksTheFrameNeeds(view, pose, params);
        ASSERT_GT(needed.size(), 500u);
        const BlockSet allocated = allocatedBlocks(scene.index()), visible = visibleBlocks(scene.index());
        EXPECT_EQ(missingFrom(needed, allocated), 0);
        EXPECT_EQ(missingFrom(needed, visible), 0);
        // Conservative, not wasteful: the sideways margin adds a thin shell (5% on the first frame, whose
        // blocks are all this frame's).
        EXPECT_LT(visible.size(), 2 * needed.size());
        if (&pose == &poses[0]) {
            EXPECT_LT(double(allocated.size()), 1.08 * double(needed.size()));
        }
        EXPECT_EQ(stats.allocation_failures_this_frame, 0);
        EXPECT_EQ(stats.blocks_allocated, int(allocated.size()));
        EXPECT_EQ(stats.visible_blocks, int(visible.size()));
        EXPECT_GE(stats.block_capacity, stats.blocks_allocated);
        EXPECT_EQ(scene.voxels().size(), std::size_t(stats.block_capacity) * kBlockVoxelCount);
    }
}

TEST_P(AllocationEngineTest, VisibleListKeepsPreviouslyVisibleBlocksWhileInTheFrustum) {
    const SceneParams params = testParams();
    HashScene scene = makeScene(params, device());
    auto allocation = makeAllocationEngine<VoxelS, VoxelBlockHash>(device());
    View view = test::renderView(world(), kIntr, poseA(), false);
    allocation->allocate(scene, view, poseA());
    const BlockSet first = visibleBlocks(scene.index());
    // The band's own blocks: neighbours just outside the image leave the list with the margin's blocks.
    const BlockSet needed = blocksTheFrameNeeds(view, poseA(), params, false);

    // No depth at all: nothing new, the blocks seen before stay visible from the same pose (all but a
    // few that the sideways margin took from just outside the image)...
    for (std::size_t i = 0; i < view.depth.pixelCount(); ++i) view.depth.host()[i] = 0.f;
    AllocationStats stats = allocation->allocate(scene, view, poseA());
    EXPECT_EQ(stats.blocks_allocated_this_frame, 0);
    const BlockSet kept = visibleBlocks(scene.index());
    EXPECT_EQ(missingFrom(kept, first), 0);
    EXPECT_EQ(missingFrom(needed, kept), 0);
    EXPECT_GT(kept.size(), first.size() * 95 / 100);
    // ...and leave the list when the camera turns away from them.
    const Mat4f away = test::lookAt({1.0f, -0.8f, 0.7f}, {2.0f, -2.0f, 0.7f});
    stats = allocation->allocate(scene, view, away);
    EXPECT_LT(stats.visible_blocks, int(first.size()) / 10);
    stats = allocation->allocate(scene, view, poseA());
    EXPECT_EQ(stats.visible_blocks, 0) << "blocks re-enter the list only when the depth sees them";
}

class AllocationCapacityTest : public ::testing::TestWithParam<std::tuple<Device, int>> {
protected:
    void SetUp() override { VF_SKIP_IF_UNAVAILABLE(device()); }
    Device device() const { return std::get<0>(GetParam()); }
    int entriesPerBucket() const { return std::get<1>(GetParam()); }
};

TEST_P(AllocationCapacityTest, FullBucketsAndExcessListAreCountedExactly) {
    const SceneParams params = testParams();
    VoxelBlockHashSettings s;
    s.bucket_count = 4;
    s.entries_per_bucket = entriesPerBucket();
    s.excess_entry_count = 8;
    HashScene scene = makeScene(params, device(), s);
    auto allocation = makeAllocationEngine<VoxelS, VoxelBlockHash>(device());
    auto integration = makeIntegrationEngine<VoxelS, VoxelBlockHash>(device());
    const View view = test::renderView(world(), kIntr, poseA(), false);
    const int walked = int(blocksOnSegments(view, poseA(), params).size());
    const int capacity = 4 * s.entries_per_bucket + 8;
    for (int frame = 1; frame <= 2; ++frame) {
        const AllocationStats stats = allocation->allocate(scene, view, poseA());
        EXPECT_EQ(stats.blocks_allocated, capacity);
        EXPECT_EQ(stats.allocation_failures_this_frame, walked - capacity);
        EXPECT_EQ(stats.failures_hash_full_this_frame, walked - capacity);
        EXPECT_EQ(stats.failures_blocks_full_this_frame, 0);
        EXPECT_EQ(stats.allocation_failures_total, (long long)frame * (walked - capacity));
        integration->integrate(scene, view, poseA());  // carries on with what it has
    }
}

INSTANTIATE_TEST_SUITE_P(DevicesAndBuckets, AllocationCapacityTest,
                         ::testing::Combine(test::kAllDevices, ::testing::Values(1, 2)),
                         [](const ::testing::TestParamInfo<std::tuple<Device, int>>& info) {
                             return std::string(deviceName(std::get<0>(info.param))) + "_" +
                                    std::to_string(std::get<1>(info.param)) + "_entries_per_bucket";
                         });

TEST_P(AllocationEngineTest, FullVoxelBlockArrayIsCountedExactly) {
    const SceneParams params = testParams();
    VoxelBlockHashSettings s;
    s.max_block_count = 50;
    s.blocks_per_growth = 16;
    HashScene scene = makeScene(params, device(), s);
    auto allocation = makeAllocationEngine<VoxelS, VoxelBlockHash>(device());
    const View view = test::renderView(world(), kIntr, poseA(), false);
    const int walked = int(blocksOnSegments(view, poseA(), params).size());
    const AllocationStats stats = allocation->allocate(scene, view, poseA());
    EXPECT_EQ(stats.blocks_allocated, 50);
    EXPECT_EQ(stats.block_capacity, 50);
    EXPECT_EQ(stats.allocation_failures_this_frame, walked - 50);
    EXPECT_EQ(stats.failures_blocks_full_this_frame, walked - 50);
    EXPECT_EQ(stats.failures_hash_full_this_frame, 0);
}

TEST_P(AllocationEngineTest, VoxelArrayGrowsWithTheSceneInSteps) {
    const SceneParams params = testParams();
    VoxelBlockHashSettings s;
    s.blocks_per_growth = 256;
    HashScene scene = makeScene(params, device(), s);
    EXPECT_EQ(scene.voxels().size(), 0u);
    auto allocation = makeAllocationEngine<VoxelS, VoxelBlockHash>(device());
    const AllocationStats a = allocation->allocate(scene, test::renderView(world(), kIntr, poseA(), false), poseA());
    EXPECT_EQ(a.block_capacity % 256, 0);
    EXPECT_LT(a.block_capacity, a.blocks_allocated + 256);
    const AllocationStats b = allocation->allocate(scene, test::renderView(world(), kIntr, poseB(), false), poseB());
    EXPECT_GT(b.blocks_allocated, a.blocks_allocated);
    EXPECT_GE(b.block_capacity, b.blocks_allocated);
    EXPECT_LT(b.block_capacity, b.blocks_allocated + std::max(256, a.block_capacity / 4) + 256);
}

TEST_P(AllocationEngineTest, RemovalFreesExactlyTheEmptyBlocksAndKeepsTheRest) {
    const SceneParams params = testParams();
    HashScene scene = makeScene(params, device());
    auto allocation = makeAllocationEngine<VoxelS, VoxelBlockHash>(device());
    auto integration = makeIntegrationEngine<VoxelS, VoxelBlockHash>(device());
    for (const Mat4f& pose : {poseA(), poseB()}) {
        const View view = test::renderView(world(), kIntr, pose, false);
        allocation->allocate(scene, view, pose);
        integration->integrate(scene, view, pose);
    }
    // A block allocated but never integrated (outside every view) must go too: added on a host copy.
    {
        HashScene host = test::onHost(scene);
        ASSERT_EQ(host.index().insert({300, 300, 300}), VoxelBlockHash::InsertResult::Inserted);
        host.voxels().fill(
            Device::CPU, VoxelS::initial(),
            std::size_t(host.index().entry(host.index().findEntry({300, 300, 300})).ptr) * kBlockVoxelCount,
            kBlockVoxelCount);
        scene = host.copyTo(device());
    }

    std::map<Key, std::vector<VoxelS>> kept;
    int empty = 0;
    {
        const HashScene host = test::onHost(scene);
        const VoxelBlockHash& hash = host.index();
        const VoxelS* voxels = host.voxels().host();
        for (int i = 0; i < hash.entryCount(); ++i) {
            const HashEntry& e = hash.entry(i);
            if (e.ptr < 0) continue;
            const VoxelS* block = voxels + e.ptr * kBlockVoxelCount;
            bool observed = false;
            for (int v = 0; v < kBlockVoxelCount; ++v) observed = observed || block[v].w_depth > 0;
            if (observed)
                kept[{e.pos.x, e.pos.y, e.pos.z}].assign(block, block + kBlockVoxelCount);
            else
                ++empty;
        }
    }
    ASSERT_GT(empty, 0);
    const int before = scene.index().blocksInUse();
    const int visible_before = scene.index().visibleCount();
    EXPECT_EQ(allocation->removeEmptyBlocks(scene), empty);
    EXPECT_EQ(scene.index().blocksInUse(), before - empty);
    EXPECT_EQ(scene.index().stats().blocks_removed_total, empty);
    EXPECT_LT(scene.index().visibleCount(), visible_before) << "removed blocks leave the visible list";
    {
        const HashScene host = test::onHost(scene);
        const VoxelBlockHash& hash = host.index();
        EXPECT_EQ(hash.findEntry({300, 300, 300}), -1);
        EXPECT_EQ(int(allocatedBlocks(hash).size()), int(kept.size()));
        for (const auto& [k, contents] : kept) {
            const int e = hash.findEntry({std::get<0>(k), std::get<1>(k), std::get<2>(k)});
            ASSERT_GE(e, 0);
            const VoxelS* block = host.voxels().host() + hash.entry(e).ptr * kBlockVoxelCount;
            for (int v = 0; v < kBlockVoxelCount; ++v) {
                ASSERT_EQ(block[v].sdf, contents[v].sdf);
                ASSERT_EQ(block[v].w_depth, contents[v].w_depth);
            }
        }
        // Every entry of the visible list still holds a block.
        for (int k = 0; k < hash.visibleCount(); ++k) ASSERT_GE(hash.entry(hash.visibleEntries()[k]).ptr, 0);
    }
    EXPECT_EQ(allocation->removeEmptyBlocks(scene), 0) << "nothing left to remove";

    // The freed blocks are reused, clean, by the next frame.
    const View view = test::renderView(world(), kIntr, poseA(), false);
    allocation->allocate(scene, view, poseA());
    integration->integrate(scene, view, poseA());
    EXPECT_EQ(missingFrom(blocksTheFrameNeeds(view, poseA(), params), allocatedBlocks(scene.index())), 0);
}

TEST_P(AllocationEngineTest, IntegrationRefusesAViewTheAllocationDidNotPrepare) {
    const SceneParams params = testParams();
    HashScene scene = makeScene(params, device());
    auto allocation = makeAllocationEngine<VoxelS, VoxelBlockHash>(device());
    auto integration = makeIntegrationEngine<VoxelS, VoxelBlockHash>(device());
    const View view = test::renderView(world(), kIntr, poseA(), false);
    EXPECT_THROW(integration->integrate(scene, view, poseA()), Error);
    allocation->allocate(scene, view, poseA());
    EXPECT_NO_THROW(integration->integrate(scene, view, poseA()));
    EXPECT_THROW(integration->integrate(scene, view, poseB()), Error);
}

TEST_P(AllocationEngineTest, DenseIndexNeedsNoAllocation) {
    Scene<VoxelS, PlainVoxelArray> scene(testParams(), PlainVoxelArray({-8, -8, -8}, {16, 16, 16}), device());
    auto allocation = makeAllocationEngine<VoxelS, PlainVoxelArray>(device());
    const AllocationStats stats =
        allocation->allocate(scene, test::renderView(world(), kIntr, poseA(), false), poseA());
    EXPECT_EQ(stats.blocks_allocated, 0);
    EXPECT_EQ(allocation->removeEmptyBlocks(scene), 0);
}

// The table is a function of the frames: the same entries, blocks and free stacks whatever the number
// of threads (the same rule makes the CPU and CUDA tables equal: tests/cuda/EngineCudaParityTest.cpp).
TEST_P(AllocationEngineTest, TheTableDoesNotDependOnTheNumberOfThreads) {
    if (device() != Device::CPU) GTEST_SKIP() << "threads are a CPU matter";
    const SceneParams params = testParams();
    VoxelBlockHashSettings small;
    small.bucket_count = 4096;  // many collisions and chains
    small.excess_entry_count = 4096;
    auto run = [&](int threads) {
        setCpuThreadCount(threads);
        HashScene scene = makeScene(params, Device::CPU, small);
        auto allocation = makeAllocationEngine<VoxelS, VoxelBlockHash>(Device::CPU);
        auto integration = makeIntegrationEngine<VoxelS, VoxelBlockHash>(Device::CPU);
        for (const Mat4f& pose : {poseA(), poseB(), poseA()}) {
            const View view = test::renderView(world(), kIntr, pose, false);
            allocation->allocate(scene, view, pose);
            integration->integrate(scene, view, pose);
        }
        allocation->removeEmptyBlocks(scene);
        setCpuThreadCount(0);
        return scene;
    };
    const HashScene one = run(1), four = run(4);
    const VoxelBlockHash &a = one.index(), &b = four.index();
    ASSERT_EQ(a.entryCount(), b.entryCount());
    ASSERT_EQ(a.freeBlocks(), b.freeBlocks());
    ASSERT_EQ(a.visibleCount(), b.visibleCount());
    ASSERT_EQ(test::firstDifferentEntry(a, b), -1);
    for (int k = 0; k < a.visibleCount(); ++k) ASSERT_EQ(a.visibleEntries()[k], b.visibleEntries()[k]);
    ASSERT_EQ(test::firstDifferentVoxel(one.voxels(), four.voxels()), -1);
}

// Blocks that want one insertion target in one frame all get in (one per round), not only the first.
TEST_P(AllocationEngineTest, CollidingNewBlocksAreAllInsertedInTheirFrame) {
    const SceneParams params = testParams();
    VoxelBlockHashSettings tiny;
    tiny.bucket_count = 16;  // hundreds of blocks in 16 buckets: long chains built in one frame
    tiny.excess_entry_count = 8192;
    HashScene scene = makeScene(params, device(), tiny);
    auto allocation = makeAllocationEngine<VoxelS, VoxelBlockHash>(device());
    const View view = test::renderView(world(), kIntr, poseA(), false);
    const AllocationStats stats = allocation->allocate(scene, view, poseA());
    const BlockSet walked = blocksOnSegments(view, poseA(), params);
    EXPECT_EQ(stats.allocation_failures_this_frame, 0);
    EXPECT_EQ(stats.blocks_allocated_this_frame, int(walked.size()));
    EXPECT_EQ(allocatedBlocks(scene.index()), walked);
}

// A frame may ask for more blocks than an int counts (a voxel size far below the depth's resolution):
// the count of appends saturates instead of overflowing into negative list slots, and the list is
// never written beyond its capacity.
TEST(AllocationStage1Test, TheCountOfMissingBlocksSaturatesAndTheListIsNeverOverrun) {
    const SceneParams params = testParams();
    const View view = test::renderView(world(), kIntr, poseA(), false);
    VoxelBlockHash hash{VoxelBlockHashSettings()};
    const int needed = int(blocksOnSegments(view, poseA(), params).size());
    ASSERT_GT(needed, 200);
    constexpr int kCapacity = 16, kCountStop = 100;
    std::vector<std::uint64_t> list(kCapacity + 8, 0xfeedull);  // 8 guard slots past the capacity
    int count = 0;
    MarkBlocksForPixels<256> mark{makeDepthSegmentFrame(params, view, poseA()),
                                  hash.data(),
                                  hash.state().entry_visibility,
                                  list.data(),
                                  &count,
                                  kCapacity,
                                  Vec2i{kIntr.width, 1}};
    mark.max_counted_appends = kCountStop;
    CpuDevice::parallelFor(mark.elementCount(), mark);
    EXPECT_GE(count, kCountStop);
    EXPECT_LE(count, kCountStop + cpuThreadCount());
    for (int i = kCapacity; i < int(list.size()); ++i) EXPECT_EQ(list[std::size_t(i)], 0xfeedull) << "slot " << i;
}

INSTANTIATE_TEST_SUITE_P(Devices, AllocationEngineTest, test::kAllDevices, test::DeviceName());

}  // namespace
}  // namespace voxfuse
