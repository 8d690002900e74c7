// Surface point clouds: extraction gives exactly the mesh's vertices, and voxel-grid downsampling puts
// one point at the centroid of each occupied cell.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "voxfuse/core/Error.h"
#include "voxfuse/engines/MeshingEngine.h"
#include "voxfuse/engines/PointCloudDownsampling.h"
#include "voxfuse/objects/Voxel.h"
#include "voxfuse/objects/VoxelBlockHash.h"
#include "voxfuse/shared/HashAccess.h"

namespace voxfuse {
namespace {

// ---- Extraction ----

constexpr float kVoxel = 0.01f, kRadius = 0.2f;

template <class TVoxel>
void fillSphere(Scene<TVoxel, VoxelBlockHash>& scene) {
    const int r = 24;  // voxels: the sphere (20) and its truncation band (4)
    const Vec3i lo = blockOfVoxel({-r, -r, -r}), hi = blockOfVoxel({r, r, r});
    scene.reserveVoxelBlocks((hi.x - lo.x + 1) * (hi.y - lo.y + 1) * (hi.z - lo.z + 1));
    for (int bz = lo.z; bz <= hi.z; ++bz)
        for (int by = lo.y; by <= hi.y; ++by)
            for (int bx = lo.x; bx <= hi.x; ++bx) {
                int entry = -1;
                ASSERT_EQ(scene.index().insert({bx, by, bz}, &entry), VoxelBlockHash::InsertResult::Inserted);
                TVoxel* block = scene.voxels().host() + std::size_t(scene.index().entry(entry).ptr) * kBlockVoxelCount;
                for (int i = 0; i < kBlockVoxelCount; ++i) {
                    const Vec3i p = Vec3i{bx, by, bz} * kBlockSide + Vec3i{i & 7, (i >> 3) & 7, i >> 6};
                    const Vec3f x = toFloat(p) * kVoxel + Vec3f{0.0031f, 0.0017f, -0.0023f};
                    block[i].sdf =
                        TVoxel::sdfFromFloat(clampValue((length(x) - kRadius) / scene.params().mu_m, -1.f, 1.f));
                    block[i].w_depth = 1;
                    if constexpr (TVoxel::hasColor) {
                        block[i].clr =
                            Vec3u8{std::uint8_t(100 + p.x), std::uint8_t(100 + p.y), std::uint8_t(100 + p.z)};
                        block[i].w_color = 1;
                    }
                }
            }
}

SceneParams params() {
    SceneParams p;
    p.voxel_size_m = kVoxel;
    p.mu_m = 0.04f;
    return p;
}

VoxelBlockHashSettings smallHash() {
    VoxelBlockHashSettings s;
    s.bucket_count = 0x4000;
    s.excess_entry_count = 0x1000;
    s.max_block_count = 0x4000;
    return s;
}

TEST(PointCloudExtraction, GivesTheMeshVerticesWithoutTriangles) {
    Scene<VoxelSRgb, VoxelBlockHash> scene(params(), VoxelBlockHash(smallHash()), Device::CPU);
    fillSphere(scene);
    auto engine = makeMeshingEngine<VoxelSRgb, VoxelBlockHash>(Device::CPU);
    Mesh mesh;
    PointCloud cloud;
    engine->extractMesh(scene, mesh);
    engine->extractPointCloud(scene, cloud);
    ASSERT_GT(cloud.size(), 3000u);
    ASSERT_EQ(cloud.points.size(), mesh.vertices.size());
    ASSERT_EQ(cloud.normals.size(), mesh.normals.size());
    ASSERT_EQ(cloud.colors.size(), mesh.colors.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        ASSERT_EQ(cloud.points[i], mesh.vertices[i]);
        ASSERT_EQ(cloud.normals[i], mesh.normals[i]);
        ASSERT_EQ(cloud.colors[i], mesh.colors[i]);
    }
}

TEST(PointCloudExtraction, VoxelTypesWithoutColorGiveNoColors) {
    Scene<VoxelF, VoxelBlockHash> scene(params(), VoxelBlockHash(smallHash()), Device::CPU);
    fillSphere(scene);
    PointCloud cloud;
    makeMeshingEngine<VoxelF, VoxelBlockHash>(Device::CPU)->extractPointCloud(scene, cloud);
    ASSERT_GT(cloud.size(), 3000u);
    EXPECT_FALSE(cloud.hasColors());
    EXPECT_EQ(cloud.normals.size(), cloud.size());
}

// ---- Downsampling ----

void expectNear(Vec3f a, Vec3f b, float tolerance) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

// Cells of 0.1 m: cell (0,0,0) gets three points, cell (-1,0,0) two (negative coordinates round down),
// cell (0,0,1) one.
PointCloud handMadeCloud() {
    PointCloud c;
    c.points = {{0.01f, 0.02f, 0.03f},  {0.09f, 0.05f, 0.01f},  {0.05f, 0.08f, 0.05f},  // cell (0, 0, 0)
                {-0.02f, 0.01f, 0.01f}, {-0.08f, 0.03f, 0.05f},                         // cell (-1, 0, 0)
                {0.05f, 0.05f, 0.15f}};                                                 // cell (0, 0, 1)
    c.normals = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, -1, 0}};
    c.colors = {{10, 20, 30}, {20, 40, 60}, {31, 61, 91}, {0, 0, 0}, {255, 255, 255}, {7, 8, 9}};
    return c;
}

TEST(PointCloudDownsampling, OnePointPerCellAtTheCentroid) {
    const PointCloud out = downsampleVoxelGrid(handMadeCloud(), 0.1f);
    ASSERT_EQ(out.size(), 3u);
    ASSERT_EQ(out.normals.size(), 3u);
    ASSERT_EQ(out.colors.size(), 3u);
    // Ordered by cell z, then y, then x: (-1,0,0), (0,0,0), (0,0,1).
    expectNear(out.points[0], {-0.05f, 0.02f, 0.03f}, 1e-7f);
    expectNear(out.points[1], {0.05f, 0.05f, 0.03f}, 1e-7f);
    expectNear(out.points[2], {0.05f, 0.05f, 0.15f}, 1e-7f);
    const float s = 1.f / std::sqrt(3.f);
    expectNear(out.normals[0], {0.f, 0.f, 1.f}, 1e-6f);
    expectNear(out.normals[1], {s, s, s}, 1e-6f);
    expectNear(out.normals[2], {0.f, -1.f, 0.f}, 1e-6f);
    EXPECT_EQ(out.colors[0], (Vec3u8{128, 128, 128}));  // 127.5 rounds up
    EXPECT_EQ(out.colors[1], (Vec3u8{20, 40, 60}));     // (10 + 20 + 31) / 3 = 20.33, ...
    EXPECT_EQ(out.colors[2], (Vec3u8{7, 8, 9}));
}

TEST(PointCloudDownsampling, CellsSmallerThanThePointSpacingKeepEveryPoint) {
    const PointCloud in = handMadeCloud();
    const PointCloud out = downsampleVoxelGrid(in, 0.001f);
    ASSERT_EQ(out.size(), in.size());
    for (const Vec3f& p : in.points) {
        bool found = false;
        for (const Vec3f& q : out.points) found = found || q == p;
        EXPECT_TRUE(found);
    }
}

TEST(PointCloudDownsampling, CloudsWithoutNormalsOrColorsAndBadPoints) {
    PointCloud in;
    in.points = {{0.f, 0.f, 0.f},
                 {std::numeric_limits<float>::quiet_NaN(), 0.f, 0.f},
                 {0.5f, 0.5f, 0.5f},
                 {std::numeric_limits<float>::infinity(), 1.f, 1.f},
                 {0.2f, 0.2f, 0.2f}};
    const PointCloud out = downsampleVoxelGrid(in, 1.f);
    ASSERT_EQ(out.size(), 1u) << "non-finite points are dropped";
    expectNear(out.points[0], {0.7f / 3.f, 0.7f / 3.f, 0.7f / 3.f}, 1e-7f);
    EXPECT_FALSE(out.hasNormals());
    EXPECT_FALSE(out.hasColors());
    EXPECT_TRUE(downsampleVoxelGrid(PointCloud(), 0.01f).empty());
}

TEST(PointCloudDownsampling, RejectsBadCellsAndInconsistentClouds) {
    EXPECT_THROW(downsampleVoxelGrid(handMadeCloud(), 0.f), ConfigError);
    EXPECT_THROW(downsampleVoxelGrid(handMadeCloud(), -0.1f), ConfigError);
    EXPECT_THROW(downsampleVoxelGrid(handMadeCloud(), std::numeric_limits<float>::quiet_NaN()), ConfigError);
    PointCloud far;
    far.points = {{1e6f, 0.f, 0.f}};
    EXPECT_THROW(downsampleVoxelGrid(far, 1e-6f), ConfigError) << "cell indices beyond 32 bits";
    PointCloud bad = handMadeCloud();
    bad.normals.pop_back();
    EXPECT_THROW(downsampleVoxelGrid(bad, 0.1f), Error);
}

// A cell's class is its points' most frequent one; kNoLabel counts only when no point has a class, and
// the smallest class wins a tie.
TEST(PointCloudDownsampling, CellsTakeTheMajorityClass) {
    PointCloud in;
    auto add = [&in](Vec3f p, ClassId label) {
        in.points.push_back(p);
        in.labels.push_back(label);
    };
    // Cell (0, 0, 0): 5 twice, 2 once, no class three times -> 5.
    for (ClassId c : {kNoLabel, ClassId(5), kNoLabel, ClassId(2), ClassId(5), kNoLabel}) add({0.05f, 0.05f, 0.05f}, c);
    // Cell (1, 0, 0): 9 and 4 twice each, in that order -> the smaller, 4.
    for (ClassId c : {ClassId(9), ClassId(4), ClassId(9), ClassId(4)}) add({0.15f, 0.05f, 0.05f}, c);
    // Cell (2, 0, 0): no class at all -> none.
    for (int k = 0; k < 2; ++k) add({0.25f, 0.05f, 0.05f}, kNoLabel);
    // Cell (3, 0, 0): a single point.
    add({0.35f, 0.05f, 0.05f}, 11);
    // Cell (4, 0, 0): 0 is a class like any other; 0, 65534 and 8 once each -> 0.
    for (ClassId c : {ClassId(65534), ClassId(8), ClassId(0)}) add({0.45f, 0.05f, 0.05f}, c);
    const PointCloud out = downsampleVoxelGrid(in, 0.1f);
    ASSERT_EQ(out.size(), 5u);
    EXPECT_EQ(out.labels, (std::vector<ClassId>{5, 4, kNoLabel, 11, 0}));
    EXPECT_FALSE(out.hasColors());

    // The order of the points does not matter.
    PointCloud reversed = in;
    std::reverse(reversed.points.begin(), reversed.points.end());
    std::reverse(reversed.labels.begin(), reversed.labels.end());
    EXPECT_EQ(downsampleVoxelGrid(reversed, 0.1f).labels, out.labels);

    EXPECT_TRUE(downsampleVoxelGrid(handMadeCloud(), 0.1f).labels.empty()) << "no labels in, none out";
    in.labels.pop_back();
    EXPECT_THROW(downsampleVoxelGrid(in, 0.1f), Error);
}

// On an extracted surface: fewer points, none farther from the sphere than half a cell.
TEST(PointCloudDownsampling, ThinsAnExtractedSurface) {
    Scene<VoxelF, VoxelBlockHash> scene(params(), VoxelBlockHash(smallHash()), Device::CPU);
    fillSphere(scene);
    PointCloud cloud;
    makeMeshingEngine<VoxelF, VoxelBlockHash>(Device::CPU)->extractPointCloud(scene, cloud);
    const float cell = 0.03f;
    const PointCloud thin = downsampleVoxelGrid(cloud, cell);
    EXPECT_LT(thin.size(), cloud.size() / 4);
    // Sphere area / cell area bounds the occupied cells from below.
    EXPECT_GT(thin.size(), std::size_t(4.f * 3.14159f * kRadius * kRadius / (cell * cell)));
    const Vec3f centre{-0.0031f, -0.0017f, 0.0023f};
    for (std::size_t i = 0; i < thin.size(); ++i) {
        const Vec3f radial = thin.points[i] - centre;
        ASSERT_LT(std::fabs(length(radial) - kRadius), 0.5f * cell);
        ASSERT_GT(dot(thin.normals[i], normalize(radial)), 0.9f);
    }
}

}  // namespace
}  // namespace voxfuse
