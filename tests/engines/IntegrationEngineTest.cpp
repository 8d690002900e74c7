// Integration against closed-form signed distances, on each device.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "DeviceTestSupport.h"
#include "SyntheticViews.h"
#include "core/CpuDevice.h"
#include "voxfuse/engines/AllocationEngine.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/objects/Voxel.h"
#include "voxfuse/shared/VoxelAccess.h"

namespace voxfuse {
namespace {

template <class TDeviceAndVoxel>
class IntegrationEngineTest : public ::testing::Test {
protected:
    void SetUp() override { VF_SKIP_IF_UNAVAILABLE(TDeviceAndVoxel::device); }
};
TYPED_TEST_SUITE(IntegrationEngineTest, test::DevicesAndVoxels, test::DeviceAndVoxelName);

SceneParams smallSceneParams() {
    SceneParams p;
    p.voxel_size_m = 0.01f;
    p.mu_m = 0.04f;
    return p;
}

// A wall facing the camera at z = 1 m: the projective SDF equals the true SDF, 1 - z, clamped to mu.
TYPED_TEST(IntegrationEngineTest, FrontoParallelPlaneMatchesAnalyticSdf) {
    using TVoxel = typename TypeParam::Voxel;
    constexpr Device device = TypeParam::device;
    const SceneParams params = smallSceneParams();
    Scene<TVoxel, PlainVoxelArray> scene(params, PlainVoxelArray({-40, -30, 0}, {80, 60, 140}), device);
    // World z up in the synthetic scene; look along world +x at a wall x = 1, then express the volume in camera
    // coordinates by making the camera the world origin: a plane at camera z = 1.
    View view;
    view.calib.depth = view.calib.rgb = test::kinectIntrinsics(160, 120);
    view.depth.resize(view.calib.depth.size());
    for (std::size_t i = 0; i < view.depth.pixelCount(); ++i) view.depth.host()[i] = 1.0f;

    auto engine = makeIntegrationEngine<TVoxel, PlainVoxelArray>(device);
    engine->integrate(scene, view, Mat4f::identity());

    const auto host = test::onHost(scene);
    const PlainVoxelArray::Data index = host.index().data();
    int checked = 0;
    for (int z = 80; z <= 120; ++z) {
        bool found;
        const TVoxel v = readVoxel(host.voxels().host(), index, Vec3i{0, 0, z}, found);
        ASSERT_TRUE(found);
        const float z_m = z * params.voxel_size_m;
        const float eta = 1.0f - z_m;
        if (eta < -params.mu_m) {
            EXPECT_EQ(v.w_depth, 0) << "voxel at z=" << z_m << " is behind the band and must not change";
            continue;
        }
        EXPECT_EQ(v.w_depth, 1);
        const float expected = std::min(1.f, eta / params.mu_m) * params.mu_m;
        EXPECT_NEAR(TVoxel::sdfToFloat(v.sdf) * params.mu_m, expected, 1e-4f) << "z=" << z_m;
        ++checked;
    }
    EXPECT_GT(checked, 20);
}

// A tilted plane seen from several poses: the fused zero crossing lies within one voxel of the plane.
TYPED_TEST(IntegrationEngineTest, TiltedPlaneZeroCrossingWithinOneVoxel) {
    using TVoxel = typename TypeParam::Voxel;
    constexpr Device device = TypeParam::device;
    const SceneParams params = smallSceneParams();
    // World: plane through (0, 0, 0) with normal (0.3, 0, 1) (z up); cameras above it looking down-ish.
    const Eigen::Vector3f normal = Eigen::Vector3f(0.3f, 0.f, 1.f).normalized();
    const synth::SyntheticScene plane = synth::SyntheticScene::singlePlane(Eigen::Vector3f::Zero(), normal);
    Scene<TVoxel, PlainVoxelArray> scene(params, PlainVoxelArray({-60, -60, -40}, {120, 120, 80}), device);
    auto engine = makeIntegrationEngine<TVoxel, PlainVoxelArray>(device);
    const Intrinsics intr = test::kinectIntrinsics(160, 120);
    for (const Eigen::Vector3f& eye :
         {Eigen::Vector3f(0.2f, 0.1f, 1.0f), Eigen::Vector3f(-0.2f, 0.1f, 0.9f), Eigen::Vector3f(0.0f, -0.3f, 1.1f)})
        engine->integrate(scene, test::renderView(plane, intr, test::lookAt(eye, Eigen::Vector3f::Zero())),
                          test::lookAt(eye, Eigen::Vector3f::Zero()));

    // Along vertical lines near the origin, find the sign change and compare with the plane's height.
    const auto host = test::onHost(scene);
    const PlainVoxelArray::Data index = host.index().data();
    int lines = 0;
    for (int x = -15; x <= 15; x += 5)
        for (int y = -15; y <= 15; y += 5) {
            float prev = 1.f;
            for (int z = 30; z > -30; --z) {
                bool found;
                const TVoxel v = readVoxel(host.voxels().host(), index, Vec3i{x, y, z}, found);
                if (v.w_depth == 0) continue;
                const float sdf = TVoxel::sdfToFloat(v.sdf);
                if (prev > 0.f && sdf <= 0.f) {
                    const float z_cross =
                        (z + sdf / (sdf - prev)) * params.voxel_size_m;  // linear interpolation between z and z+1
                    const float z_plane = -(normal.x() * x * params.voxel_size_m) / normal.z();
                    EXPECT_NEAR(z_cross, z_plane, params.voxel_size_m) << "x=" << x << " y=" << y;
                    ++lines;
                    break;
                }
                prev = sdf;
            }
        }
    EXPECT_GE(lines, 40);
}

TYPED_TEST(IntegrationEngineTest, WeightIsCappedAndInvalidDepthIgnored) {
    using TVoxel = typename TypeParam::Voxel;
    constexpr Device device = TypeParam::device;
    SceneParams params = smallSceneParams();
    params.max_weight = 3;
    Scene<TVoxel, PlainVoxelArray> scene(params, PlainVoxelArray({-40, -30, 0}, {80, 60, 140}), device);
    View view;
    view.calib.depth = view.calib.rgb = test::kinectIntrinsics(160, 120);
    view.depth.resize(view.calib.depth.size());
    for (std::size_t i = 0; i < view.depth.pixelCount(); ++i) view.depth.host()[i] = (i % 2) ? 1.0f : NAN;
    auto engine = makeIntegrationEngine<TVoxel, PlainVoxelArray>(device);
    for (int k = 0; k < 6; ++k) engine->integrate(scene, view, Mat4f::identity());
    const auto host = test::onHost(scene);
    int max_w = 0;
    for (std::size_t i = 0; i < host.voxels().size(); ++i) {
        max_w = std::max<int>(max_w, host.voxels().host()[i].w_depth);
        ASSERT_FALSE(std::isnan(TVoxel::sdfToFloat(host.voxels().host()[i].sdf)));
    }
    EXPECT_EQ(max_w, 3);
}

class IntegrationColorTest : public ::testing::TestWithParam<Device> {
protected:
    void SetUp() override { VF_SKIP_IF_UNAVAILABLE(GetParam()); }
};

TEST_P(IntegrationColorTest, ColorOfAUniformWallIsFused) {
    const SceneParams params = smallSceneParams();
    Scene<VoxelSRgb, PlainVoxelArray> scene(params, PlainVoxelArray({-40, -30, 0}, {80, 60, 140}), GetParam());
    View view;
    view.calib.depth = view.calib.rgb = test::kinectIntrinsics(160, 120);
    view.depth.resize(view.calib.depth.size());
    view.rgb.resize(view.calib.rgb.size());
    for (std::size_t i = 0; i < view.depth.pixelCount(); ++i) {
        view.depth.host()[i] = 1.0f;
        view.rgb.host()[i] = Vec4u8{200, 100, 50, 255};
    }
    auto engine = makeIntegrationEngine<VoxelSRgb, PlainVoxelArray>(GetParam());
    engine->integrate(scene, view, Mat4f::identity());
    const auto host = test::onHost(scene);
    bool found;
    const VoxelSRgb v = readVoxel(host.voxels().host(), host.index().data(), Vec3i{0, 0, 100}, found);
    EXPECT_EQ(v.w_color, 1);
    EXPECT_EQ(v.clr.x, 200);
    EXPECT_EQ(v.clr.y, 100);
    EXPECT_EQ(v.clr.z, 50);
    const VoxelSRgb far_in_front = readVoxel(host.voxels().host(), host.index().data(), Vec3i{0, 0, 50}, found);
    EXPECT_EQ(far_in_front.w_color, 0) << "only voxels near the surface take colour";
}

INSTANTIATE_TEST_SUITE_P(Devices, IntegrationColorTest, test::kAllDevices, test::DeviceName());

// The branch-free pixel lookup the CPU vectorises picks the pixel nearest to the projection (a plain
// rounding, checked here against the image's bounds), and none for voxels closer than near_m, on the
// image's borders, beyond them and for NaN.
TEST(IntegrationPixelTest, DepthPixelOfAVoxelIsTheNearestPixel) {
    IntegrationFrame f{};
    f.depth_intrinsics = test::kinectIntrinsics(160, 120);
    f.near_m = 0.2f;
    const Intrinsics& in = f.depth_intrinsics;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> lateral(-1.5f, 1.5f), depth(-0.5f, 3.f);
    int inside = 0;
    for (int k = 0; k < 200000; ++k) {
        Vec3f p{lateral(rng), lateral(rng), depth(rng)};
        if (k % 1000 == 0) p.z = f.near_m;  // exactly at the near plane: taken
        if (k % 1000 == 1) p.x = std::numeric_limits<float>::quiet_NaN();
        if (k % 1000 == 2) {  // on a pixel border half a pixel outside
            p.z = 1.f;
            p.x = (-0.5f - in.cx) / in.fx;
        }
        const Vec2f px = in.project(p);
        const float u = std::floor(px.x + 0.5f), v = std::floor(px.y + 0.5f);  // false comparisons for NaN below
        const bool on_image = u >= 0.f && v >= 0.f && u < float(in.width) && v < float(in.height);
        const int expected = p.z >= f.near_m && on_image ? int(u) + int(v) * in.width : -1;
        ASSERT_EQ(depthPixelOfVoxel(p, f), expected) << p.x << " " << p.y << " " << p.z;
        inside += expected >= 0;
    }
    EXPECT_GT(inside, 20000);  // the cases inside the image were many
}

// The frustum clipping of rows must not drop any voxel the per-voxel update would change.
TEST(IntegrationBoxTest, RowClippingLosesNoUpdate) {
    const SceneParams params = smallSceneParams();
    const synth::SyntheticScene world = synth::SyntheticScene::boxAndSphere();
    const Intrinsics intr = test::kinectIntrinsics(160, 120);
    const Mat4f pose = test::lookAt({0.9f, -0.7f, 0.8f}, {0.2f, 0.f, 0.1f});
    const View view = test::renderView(world, intr, pose);
    Scene<VoxelF, PlainVoxelArray> clipped(params, PlainVoxelArray({-60, -60, -20}, {140, 120, 80}), Device::CPU);
    makeIntegrationEngine<VoxelF, PlainVoxelArray>(Device::CPU)->integrate(clipped, view, pose);

    // Brute force: every voxel, no clipping.
    Scene<VoxelF, PlainVoxelArray> brute(params, PlainVoxelArray({-60, -60, -20}, {140, 120, 80}), Device::CPU);
    const IntegrationFrame frame = makeIntegrationFrame(params, view, pose, view.depth.host(), view.rgb.host(),
                                                        view.labels.host(), brute.takeIntegrationNumber());
    const PlainVoxelArray::Data idx = brute.index().data();
    for (int z = 0; z < idx.size.z; ++z)
        for (int y = 0; y < idx.size.y; ++y)
            for (int x = 0; x < idx.size.x; ++x)
                integrateVoxel(brute.voxels().host()[x + idx.size.x * (y + idx.size.y * z)],
                               Vec3i{x, y, z} + idx.offset, frame);
    int updated = 0;
    for (std::size_t i = 0; i < brute.voxels().size(); ++i) {
        ASSERT_EQ(brute.voxels().host()[i].w_depth, clipped.voxels().host()[i].w_depth) << "voxel " << i;
        ASSERT_EQ(brute.voxels().host()[i].sdf, clipped.voxels().host()[i].sdf) << "voxel " << i;
        updated += brute.voxels().host()[i].w_depth;
    }
    EXPECT_GT(updated, 10000);
}

// Hash integration skips visible blocks none of whose voxels the frame can update (BlockNeedsIntegration).
// Across frames from around a box and a sphere, whose visible lists hold blocks behind the surfaces
// and blocks with no depth in front: every block skipped is one that integrating all voxels leaves
// unchanged, and the scene is bit for bit the scene of integrating every visible block.
TEST(IntegrationBlockSkipTest, SkippedBlocksAreOnesNoVoxelOfWhichChanges) {
    const SceneParams params = smallSceneParams();
    const synth::SyntheticScene world = synth::SyntheticScene::boxAndSphere();
    const Intrinsics intr = test::kinectIntrinsics(160, 120);
    using HashScene = Scene<VoxelSRgb, VoxelBlockHash>;
    HashScene scene(params, VoxelBlockHash(VoxelBlockHashSettings()), Device::CPU);
    auto allocation = makeAllocationEngine<VoxelSRgb, VoxelBlockHash>(Device::CPU);
    auto integration = makeIntegrationEngine<VoxelSRgb, VoxelBlockHash>(Device::CPU);
    int skipped_total = 0, visible_total = 0;
    for (const Eigen::Vector3f& eye : {Eigen::Vector3f(0.9f, -0.7f, 0.8f), Eigen::Vector3f(-0.6f, -0.9f, 0.6f),
                                       Eigen::Vector3f(0.1f, 1.0f, 0.9f), Eigen::Vector3f(1.1f, 0.3f, 0.5f)}) {
        const Mat4f pose = test::lookAt(eye, {0.2f, 0.f, 0.1f});
        const View view = test::renderView(world, intr, pose);
        allocation->allocate(scene, view, pose);
        const VoxelBlockHash& hash = scene.index();
        const int visible = hash.visibleCount();
        const std::vector<int> visible_entries(hash.visibleEntries(), hash.visibleEntries() + visible);

        // Reference: every voxel of every visible block, on a copy.
        HashScene all = scene.copyTo(Device::CPU);
        const IntegrationFrame frame = makeIntegrationFrame(params, view, pose, view.depth.host(), view.rgb.host(),
                                                            nullptr, all.takeIntegrationNumber());
        CpuDevice::parallelFor(
            visible, IntegrateHashVoxels<VoxelSRgb, kBlockVoxelCount>{all.voxelData(), all.index().data().entries,
                                                                      visible_entries.data(), visible, frame});
        // Which blocks the engine skips.
        const int tiles_x = (intr.width + kDepthTile - 1) / kDepthTile,
                  tiles_y = (intr.height + kDepthTile - 1) / kDepthTile;
        std::vector<float> tile_max(std::size_t(tiles_x * tiles_y));
        std::vector<unsigned char> keep(static_cast<std::size_t>(visible));
        CpuDevice::parallelFor(tiles_x * tiles_y, DepthMaxTiles{view.depth.host(), intr.size(), frame.min_depth_m,
                                                                frame.max_depth_m, tiles_x, tile_max.data()});
        const BlockProjection projection{frame.T_depth_world, intr, params.voxel_size_m, frame.near_m,
                                         frame.max_depth_m + params.mu_m};
        CpuDevice::parallelFor(
            visible, BlockNeedsIntegration{hash.data().entries, visible_entries.data(), projection, params.mu_m,
                                           tile_max.data(), tiles_x, tiles_y, keep.data()});
        const HashScene before = scene.copyTo(Device::CPU);
        for (int k = 0; k < visible; ++k) {
            if (keep[std::size_t(k)]) continue;
            ++skipped_total;
            const int ptr = hash.entry(visible_entries[std::size_t(k)]).ptr;
            ASSERT_EQ(std::memcmp(before.voxels().host() + std::size_t(ptr) * kBlockVoxelCount,
                                  all.voxels().host() + std::size_t(ptr) * kBlockVoxelCount,
                                  sizeof(VoxelSRgb) * kBlockVoxelCount),
                      0)
                << "a skipped block has voxels the frame updates";
        }
        visible_total += visible;

        integration->integrate(scene, view, pose);
        ASSERT_EQ(std::memcmp(scene.voxels().host(), all.voxels().host(),
                              sizeof(VoxelSRgb) * std::size_t(hash.blocksInUse()) * kBlockVoxelCount),
                  0)
            << "skipping blocks changed the map";
    }
    EXPECT_GT(skipped_total, visible_total / 30) << "the frames should leave blocks to skip";
    std::printf("[ skip     ] %d of %d visible blocks skipped over 4 frames\n", skipped_total, visible_total);
}

}  // namespace
}  // namespace voxfuse
