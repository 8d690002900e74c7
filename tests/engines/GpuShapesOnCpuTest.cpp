// The CUDA layers' launch shapes run on the CPU: the engine stages (src/engines/*_Impl.h) with one
// item per element, as on the GPU (a pixel per stage-1 element, a voxel per integration element, a
// ray per raycast element, the dense frustum box voxel by voxel, meshing teams of several threads
// meeting at barriers), must give exactly what the CPU layer's wide elements give. Together with the
// device-parametrised engine tests this runs every loop body a CUDA kernel runs, in the normal test suite; what remains
// GPU-only is the launch, the atomics' device branch and the CUB primitives (tests/cuda/CudaDeviceTest.cu).

#include <gtest/gtest.h>

#include <omp.h>

#include <cstdio>
#include <cstring>
#include <memory>

#include "DeviceTestSupport.h"
#include "SyntheticViews.h"
#include "core/CpuDevice.h"
#include "engines/AllocationEngine_Impl.h"
#include "engines/IntegrationEngine_Impl.h"
#include "engines/LowLevelEngine_Impl.h"
#include "engines/MeshingEngine_Impl.h"
#include "engines/RaycastEngine_Impl.h"
#include "voxfuse/objects/Voxel.h"

namespace voxfuse {
namespace {

// The CPU launcher and memory with the GPU's launch shapes.
struct CpuDeviceWithGpuShapes : CpuDevice {
    static constexpr bool kOneThreadPerItem = true;

    // Teams of five threads (an odd size, so that the loops' strides end unevenly), one item at a time:
    // every thread runs the body, splits the work by its rank and waits at each team.sync(). Shared
    // memory is poisoned before every item: a body that reads what no thread of its team wrote for
    // this item fails here as it would on the GPU.
    static constexpr int kThreadsPerTeam = 5;
    template <class Shared, class Body>
    static void parallelForTeams(int n, const Body& body) {
        const std::unique_ptr<Shared> shared = cpu_detail::uninitialisedShared<Shared>();
        for (int i = 0; i < n; ++i) {
            cpu_detail::poisonShared(*shared);
#pragma omp parallel num_threads(kThreadsPerTeam)
            body(Team{omp_get_thread_num(), omp_get_num_threads()}, i, *shared);
        }
    }
};

template <class TVoxel>
class GpuShapesOnCpuTest : public ::testing::Test {};
using VoxelTypes = ::testing::Types<VoxelS, VoxelFRgb, VoxelSRgbLabel>;
TYPED_TEST_SUITE(GpuShapesOnCpuTest, VoxelTypes);

std::vector<Mat4f> poses() {
    std::vector<Mat4f> v;
    for (int k = 0; k < 3; ++k)
        v.push_back(test::lookAt({1.0f - 0.25f * k, -0.8f + 0.4f * k, 0.7f}, {0.3f, 0.f, 0.1f}));
    return v;
}

View labelledView(const Mat4f& pose, int k) {
    static const synth::SyntheticScene world = synth::SyntheticScene::boxAndSphere();
    return test::labelledView(world, test::kinectIntrinsics(160, 120), pose, k);
}

template <class TVoxel>
void expectSameVoxels(const MemoryBlock<TVoxel>& a, const MemoryBlock<TVoxel>& b) {
    ASSERT_EQ(test::firstDifferentVoxel(a, b), -1) << "voxels differ";
}

template <class T>
void expectSameArray(const std::vector<T>& a, const std::vector<T>& b, const char* what) {
    ASSERT_EQ(a.size(), b.size()) << what;
    if (!a.empty()) {
        ASSERT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(T))) << what;
    }
}

// The scene's mesh and cloud by teams of one thread and of several.
template <class TVoxel, class TIndex>
void expectSameSurfaceFromBothTeamShapes(const Scene<TVoxel, TIndex>& scene) {
    auto one = makeMeshingEngineOn<CpuDevice, TVoxel, TIndex>();
    auto several = makeMeshingEngineOn<CpuDeviceWithGpuShapes, TVoxel, TIndex>();
    Mesh ma, mb;
    one->extractMesh(scene, ma);
    several->extractMesh(scene, mb);
    EXPECT_GT(ma.triangles.size(), 2000u);
    expectSameArray(ma.vertices, mb.vertices, "vertices");
    expectSameArray(ma.normals, mb.normals, "normals");
    expectSameArray(ma.colors, mb.colors, "colours");
    expectSameArray(ma.labels, mb.labels, "classes");
    expectSameArray(ma.triangles, mb.triangles, "triangles");
    PointCloud ca, cb;
    one->extractPointCloud(scene, ca);
    several->extractPointCloud(scene, cb);
    expectSameArray(ca.points, ma.vertices, "cloud points");
    expectSameArray(ca.points, cb.points, "cloud points");
    expectSameArray(ca.labels, cb.labels, "cloud classes");
}

void expectSameRaycast(const RenderState& a, const RenderState& b) {
    ASSERT_EQ(0, std::memcmp(a.points_world.host(), b.points_world.host(), a.points_world.memory().bytes()));
    ASSERT_EQ(0, std::memcmp(a.normals_world.host(), b.normals_world.host(), a.normals_world.memory().bytes()));
    ASSERT_EQ(0, std::memcmp(a.depth_range.host(), b.depth_range.host(), a.depth_range.memory().bytes()));
    int hits = 0;
    for (std::size_t i = 0; i < a.points_world.pixelCount(); ++i) hits += a.points_world.host()[i].w > 0.f;
    EXPECT_GT(hits, 3000);
}

// Stage 1 at the GPU's shape on a full 640 x 480 frame at 5 mm: each team appends a block once per
// tile, so the list's first size holds the frame in one pass, and the table is the CPU layer's entry
// for entry. A pixel per thread without the team's set appended more keys than that size.
TEST(GpuShapesOnCpuAllocationTest, TeamsAppendEachBlockOncePerTileAndBuildTheCpuTable) {
    static const synth::SyntheticScene room = synth::SyntheticScene::defaultRoom();
    SceneParams params = test::centimetreSceneParams(4.f);
    params.voxel_size_m = 0.005f;
    params.mu_m = 0.02f;
    const Intrinsics intr = test::kinectIntrinsics(640, 480);
    Scene<VoxelS, VoxelBlockHash> wide(params, VoxelBlockHash(), Device::CPU),
        narrow(params, VoxelBlockHash(), Device::CPU);
    auto wide_allocation = makeAllocationEngineOn<CpuDevice, VoxelS, VoxelBlockHash>();
    auto narrow_allocation = makeAllocationEngineOn<CpuDeviceWithGpuShapes, VoxelS, VoxelBlockHash>();
    const Mat4f poses[2] = {test::lookAt({0.3f, -0.4f, 1.4f}, {0.f, 1.5f, 0.8f}),
                            test::lookAt({0.4f, -0.3f, 1.45f}, {0.2f, 1.5f, 0.7f})};
    for (const Mat4f& pose : poses) {
        const View view = test::renderView(room, intr, pose, false);
        // The shape the GPU ran before: a pixel per thread with a one-block cache, counted without storing.
        int per_pixel_appends = 0;
        const MarkBlocksForPixels<1> per_pixel{makeDepthSegmentFrame(params, view, pose),
                                               narrow.index().data(),
                                               narrow.index().state().entry_visibility,
                                               nullptr,
                                               &per_pixel_appends,
                                               0,
                                               Vec2i{1, 1}};
        CpuDevice::parallelFor(per_pixel.elementCount(), per_pixel);
        const AllocationStats a = wide_allocation->allocate(wide, view, pose),
                              b = narrow_allocation->allocate(narrow, view, pose);
        EXPECT_LT(10 * b.missing_block_appends_this_frame, per_pixel_appends) << "the team's set saves most appends";
        EXPECT_GT(a.blocks_allocated, 2000);
        EXPECT_EQ(a.blocks_allocated_this_frame, b.blocks_allocated_this_frame);
        EXPECT_EQ(a.allocation_failures_this_frame, 0);
        EXPECT_EQ(b.allocation_failures_this_frame, 0);
        EXPECT_EQ(b.stage1_passes_this_frame, 1) << b.missing_block_appends_this_frame << " appends";
        // Tiles of 16 x 16 pixels against the CPU's 32 x 32: about four times the repeats at most.
        EXPECT_LE(b.missing_block_appends_this_frame, 4 * a.missing_block_appends_this_frame + 100);
        EXPECT_GE(b.missing_block_appends_this_frame, b.blocks_allocated_this_frame);
        std::printf("stage 1 appends: CPU shape %d, GPU shape %d, a pixel per thread %d; blocks allocated %d (of %d)\n",
                    a.missing_block_appends_this_frame, b.missing_block_appends_this_frame, per_pixel_appends,
                    b.blocks_allocated_this_frame, b.blocks_allocated);
    }
    ASSERT_EQ(test::firstDifferentEntry(wide.index(), narrow.index()), -1) << "tables differ";
}

TYPED_TEST(GpuShapesOnCpuTest, HashPipelineGivesTheSameTableVoxelsRaysAndRenders) {
    using TVoxel = TypeParam;
    const SceneParams params = test::centimetreSceneParams();
    Scene<TVoxel, VoxelBlockHash> wide(params, VoxelBlockHash(), Device::CPU),
        narrow(params, VoxelBlockHash(), Device::CPU);
    auto wide_allocation = makeAllocationEngineOn<CpuDevice, TVoxel, VoxelBlockHash>();
    auto narrow_allocation = makeAllocationEngineOn<CpuDeviceWithGpuShapes, TVoxel, VoxelBlockHash>();
    auto wide_integration = makeIntegrationEngineOn<CpuDevice, TVoxel, VoxelBlockHash>();
    auto narrow_integration = makeIntegrationEngineOn<CpuDeviceWithGpuShapes, TVoxel, VoxelBlockHash>();
    auto wide_raycast = makeRaycastEngineOn<CpuDevice, TVoxel, VoxelBlockHash>();
    auto narrow_raycast = makeRaycastEngineOn<CpuDeviceWithGpuShapes, TVoxel, VoxelBlockHash>();
    int k = 0;
    for (const Mat4f& pose : poses()) {
        const View view = labelledView(pose, k++);
        const AllocationStats a = wide_allocation->allocate(wide, view, pose),
                              b = narrow_allocation->allocate(narrow, view, pose);
        EXPECT_EQ(a.blocks_allocated_this_frame, b.blocks_allocated_this_frame);
        EXPECT_EQ(a.visible_blocks, b.visible_blocks);
        wide_integration->integrate(wide, view, pose);
        narrow_integration->integrate(narrow, view, pose);
        RenderState ra, rb;
        // With the map's intensity read in the rays' pass (one ray per element at the GPU's shape): the
        // separate pass's values.
        wide_raycast->raycast(wide, view.calib.depth, pose, ra, RaycastNormals::SdfGradient, nullptr, true);
        narrow_raycast->raycast(narrow, view.calib.depth, pose, rb, RaycastNormals::SdfGradient, nullptr, true);
        expectSameRaycast(ra, rb);
        Image<float> separate;
        narrow_raycast->renderIntensity(narrow, rb, separate);
        ASSERT_EQ(0, std::memcmp(ra.intensity.host(), rb.intensity.host(), ra.intensity.memory().bytes()));
        ASSERT_EQ(0, std::memcmp(separate.host(), rb.intensity.host(), separate.memory().bytes()));
        for (RenderMode mode : {RenderMode::Shaded, RenderMode::Color, RenderMode::Class}) {
            Image<Vec4u8> ia, ib;
            wide_raycast->render(wide, ra, mode, ia);
            narrow_raycast->render(narrow, rb, mode, ib);
            ASSERT_EQ(0, std::memcmp(ia.host(), ib.host(), ia.memory().bytes()));
        }
    }
    EXPECT_EQ(wide_allocation->removeEmptyBlocks(wide), narrow_allocation->removeEmptyBlocks(narrow));
    const VoxelBlockHash &ha = wide.index(), &hb = narrow.index();
    ASSERT_EQ(test::firstDifferentEntry(ha, hb), -1) << "tables differ";
    expectSameVoxels(wide.voxels(), narrow.voxels());

    // A free viewpoint: the depth ranges come from every allocated block, not the visible list.
    const Mat4f free_view = test::lookAt({0.2f, 1.1f, 0.9f}, {0.2f, 0.f, 0.1f});
    RenderState ra, rb;
    wide_raycast->raycast(wide, test::kinectIntrinsics(160, 120), free_view, ra);
    narrow_raycast->raycast(narrow, test::kinectIntrinsics(160, 120), free_view, rb);
    expectSameRaycast(ra, rb);
    expectSameSurfaceFromBothTeamShapes(wide);
}

TYPED_TEST(GpuShapesOnCpuTest, DenseIntegrationVoxelByVoxelEqualsTheClippedRows) {
    using TVoxel = TypeParam;
    const SceneParams params = test::centimetreSceneParams();
    const PlainVoxelArray index({-60, -60, -20}, {140, 120, 80});
    Scene<TVoxel, PlainVoxelArray> rows(params, index, Device::CPU), voxels(params, index, Device::CPU);
    auto row_integration = makeIntegrationEngineOn<CpuDevice, TVoxel, PlainVoxelArray>();
    auto voxel_integration = makeIntegrationEngineOn<CpuDeviceWithGpuShapes, TVoxel, PlainVoxelArray>();
    auto row_raycast = makeRaycastEngineOn<CpuDevice, TVoxel, PlainVoxelArray>();
    auto voxel_raycast = makeRaycastEngineOn<CpuDeviceWithGpuShapes, TVoxel, PlainVoxelArray>();
    int k = 0;
    for (const Mat4f& pose : poses()) {
        const View view = labelledView(pose, k++);
        row_integration->integrate(rows, view, pose);
        voxel_integration->integrate(voxels, view, pose);
    }
    expectSameVoxels(rows.voxels(), voxels.voxels());
    RenderState ra, rb;
    row_raycast->raycast(rows, test::kinectIntrinsics(160, 120), poses().back(), ra);
    voxel_raycast->raycast(voxels, test::kinectIntrinsics(160, 120), poses().back(), rb);
    expectSameRaycast(ra, rb);
    expectSameSurfaceFromBothTeamShapes(rows);
}

// A rendered view of the box and sphere from the first pose, every `dropout_every`-th depth pixel emptied.
View viewWithDropouts(Vec2i size, bool color, int dropout_every) {
    static const synth::SyntheticScene world = synth::SyntheticScene::boxAndSphere();
    View view = test::renderView(world, test::kinectIntrinsics(size.x, size.y), poses()[0], color);
    for (int i = 0; i < int(view.depth.pixelCount()); i += dropout_every) view.depth.host()[i] = 0.f;
    return view;
}

// The bilateral filter by strips, each pair weighed once (CPU), and pixel by pixel (GPU): the same bits, on
// a rendered frame with holes, a size that is no multiple of the strip's, and every window size (strips
// narrow as the radius grows).
TEST(GpuShapesOnCpuLowLevelTest, BilateralFilterByStripsEqualsPixelByPixel) {
    const View view = viewWithDropouts({330, 250}, false, 13);
    LowLevelEngineOn<CpuDevice> spans;
    LowLevelEngineOn<CpuDeviceWithGpuShapes> pixels;
    for (int radius = 0; radius <= kMaxBilateralRadius; ++radius) {
        BilateralFilterParams p;
        p.radius_px = radius;
        Image<float> a, b;
        spans.bilateralFilterDepth(view.depth, a, p);
        pixels.bilateralFilterDepth(view.depth, b, p);
        ASSERT_EQ(a.size(), b.size());
        EXPECT_EQ(0, std::memcmp(a.host(), b.host(), a.pixelCount() * sizeof(float))) << "radius " << radius;
    }
}

// Cell averages (the relocaliser's code images) by cell rows in column chunks (CPU) and cell by cell
// (GPU): the same bits, for grids whose cells are 2-3 pixels wide (many to a chunk), for cells wider
// than a chunk (column by column), for grids finer than the image (cells without pixels), and for colour.
TEST(GpuShapesOnCpuLowLevelTest, CellAveragesByRowsEqualCellByCell) {
    const View view = viewWithDropouts({601, 451}, true, 7);
    LowLevelEngineOn<CpuDevice> rows;
    LowLevelEngineOn<CpuDeviceWithGpuShapes> cells;
    for (const Vec2i grid : {Vec2i{80, 60}, Vec2i{211, 160}, Vec2i{2, 3}, Vec2i{601, 451}, Vec2i{700, 500}}) {
        Image<Vec2f> a, b;
        rows.averageDepthCells(view.depth, grid, a);
        cells.averageDepthCells(view.depth, grid, b);
        ASSERT_EQ(a.size(), grid);
        ASSERT_EQ(b.size(), grid);
        EXPECT_EQ(0, std::memcmp(a.host(), b.host(), a.pixelCount() * sizeof(Vec2f)))
            << "depth, " << grid.x << "x" << grid.y << " cells";
        rows.averageIntensityCells(view.rgb, grid, a);
        cells.averageIntensityCells(view.rgb, grid, b);
        EXPECT_EQ(0, std::memcmp(a.host(), b.host(), a.pixelCount() * sizeof(Vec2f)))
            << "intensity, " << grid.x << "x" << grid.y << " cells";
    }
    // A grid finer than the image: the cells without a pixel say so.
    Image<Vec2f> out;
    rows.averageDepthCells(view.depth, Vec2i{1202, 2}, out);
    EXPECT_EQ(out.host()[1].x, 0.f);
    EXPECT_EQ(out.host()[1].y, 0.f) << "cell 1 of 1202 across 601 columns holds none";
    double counted = 0.0, valid = 0.0;
    for (std::size_t i = 0; i < out.pixelCount(); ++i) counted += out.host()[i].y;
    for (std::size_t i = 0; i < view.depth.pixelCount(); ++i) valid += view.depth.host()[i] > 0.f;
    EXPECT_EQ(counted, valid) << "every valid pixel in exactly one cell";
    EXPECT_THROW(rows.averageDepthCells(view.depth, Vec2i{0, 10}, out), Error) << "a grid without cells";
}

}  // namespace
}  // namespace voxfuse
