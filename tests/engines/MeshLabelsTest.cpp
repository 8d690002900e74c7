// Class selection on meshes and clouds: the triangle class rule, Keep and Exclude with compaction,
// per-class meshes that partition the mesh, and refusal of unlabelled input.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <tuple>
#include <vector>

#include "voxfuse/core/Error.h"
#include "voxfuse/engines/MeshLabels.h"

namespace voxfuse {
namespace {

constexpr ClassId kNone = kNoLabel;

// Eight vertices whose position, normal and colour all tell their index; triangles chosen to reach
// every case of the class rule (see the comments).
Mesh handMadeMesh() {
    Mesh m;
    for (int i = 0; i < 8; ++i) {
        m.vertices.push_back({float(i), float(i % 3), float(i % 2)});
        m.normals.push_back(normalize(Vec3f{1.f, float(i), 0.f}));
        m.colors.push_back({std::uint8_t(10 * i), std::uint8_t(10 * i + 1), std::uint8_t(10 * i + 2)});
    }
    m.labels = {1, 1, 2, 2, 1, kNone, kNone, 3};
    m.triangles = {
        {0, 1, 2},  // 1 1 2: first two agree -> 1
        {2, 3, 0},  // 2 2 1 -> 2
        {2, 0, 3},  // 2 1 2: first and last agree -> 2
        {0, 2, 3},  // 1 2 2: last two agree, not the first vertex's -> 2
        {7, 2, 4},  // 3 2 1: none agree -> the first vertex's, 3
        {4, 5, 6},  // 1 - -: two without a class -> kNoLabel
        {1, 4, 0},  // 1 1 1 -> 1
        {5, 7, 3},  // - 3 2: none agree -> the first vertex's, kNoLabel
    };
    return m;
}

const std::vector<ClassId> kHandMadeTriangleClasses = {1, 2, 2, 2, 3, kNone, 1, kNone};

// Each triangle of `part` is triangle kept[k] of `mesh`: same corners with the same attributes.
void expectTrianglesOf(const Mesh& part, const Mesh& mesh, const std::vector<std::size_t>& kept) {
    ASSERT_EQ(part.triangles.size(), kept.size());
    ASSERT_EQ(part.normals.size(), part.vertices.size());
    ASSERT_EQ(part.colors.size(), part.vertices.size());
    ASSERT_EQ(part.labels.size(), part.vertices.size());
    for (std::size_t k = 0; k < kept.size(); ++k)
        for (int c = 0; c < 3; ++c) {
            const std::size_t a = std::size_t(part.triangles[k][c]), b = std::size_t(mesh.triangles[kept[k]][c]);
            ASSERT_LT(a, part.vertices.size());
            EXPECT_EQ(part.vertices[a], mesh.vertices[b]);
            EXPECT_EQ(part.normals[a], mesh.normals[b]);
            EXPECT_EQ(part.colors[a], mesh.colors[b]);
            EXPECT_EQ(part.labels[a], mesh.labels[b]);
        }
    // Only used vertices, each once, in their original order (positions ascend in x here).
    std::vector<int> uses(part.vertices.size(), 0);
    for (const Vec3i& t : part.triangles)
        for (int c = 0; c < 3; ++c) ++uses[std::size_t(t[c])];
    EXPECT_EQ(std::count(uses.begin(), uses.end(), 0), 0);
    for (std::size_t v = 1; v < part.vertices.size(); ++v) EXPECT_LT(part.vertices[v - 1].x, part.vertices[v].x);
}

void expectEqualMeshes(const Mesh& a, const Mesh& b) {
    EXPECT_EQ(a.vertices, b.vertices);
    EXPECT_EQ(a.normals, b.normals);
    EXPECT_EQ(a.colors, b.colors);
    EXPECT_EQ(a.labels, b.labels);
    EXPECT_EQ(a.triangles, b.triangles);
}

TEST(MeshLabels, TriangleClassIsTheMajorityElseTheFirstVertexs) {
    const Mesh m = handMadeMesh();
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
        EXPECT_EQ(triangleClass(m, t), kHandMadeTriangleClasses[t]) << "triangle " << t;
    EXPECT_EQ(classesOf(m), (std::vector<ClassId>{1, 2, 3, kNone}));
    EXPECT_THROW(triangleClass(m, m.triangles.size()), Error);
}

TEST(MeshLabels, KeepAndExcludeCompactTheVertices) {
    const Mesh m = handMadeMesh();
    const Mesh twos = selectClasses(m, {2}, ClassSelection::Keep);
    expectTrianglesOf(twos, m, {1, 2, 3});
    EXPECT_EQ(twos.vertices, (std::vector<Vec3f>{m.vertices[0], m.vertices[2], m.vertices[3]}));
    EXPECT_EQ(twos.triangles, (std::vector<Vec3i>{{1, 2, 0}, {1, 0, 2}, {0, 1, 2}}));
    EXPECT_EQ(twos.labels, (std::vector<ClassId>{1, 2, 2})) << "vertices keep their own labels";

    const Mesh kept = selectClasses(m, {3, 1}, ClassSelection::Keep);  // any order, duplicates allowed
    expectTrianglesOf(kept, m, {0, 4, 6});
    expectEqualMeshes(selectClasses(m, {1, 3, 1}, ClassSelection::Keep), kept);

    const Mesh excluded = selectClasses(m, {2, kNone}, ClassSelection::Exclude);
    expectTrianglesOf(excluded, m, {0, 4, 6});
    expectEqualMeshes(excluded, kept);
    EXPECT_EQ(excluded.vertices.size(), 5u);  // 0 1 2 4 7

    expectTrianglesOf(selectClasses(m, {kNone}, ClassSelection::Keep), m, {5, 7});
    expectEqualMeshes(selectClasses(m, {}, ClassSelection::Exclude), m);
    const Mesh nothing = selectClasses(m, {42}, ClassSelection::Keep);
    EXPECT_TRUE(nothing.vertices.empty());
    EXPECT_TRUE(nothing.triangles.empty());

    // Attributes the mesh lacks stay absent.
    Mesh bare = m;
    bare.normals.clear();
    bare.colors.clear();
    const Mesh bare_twos = selectClasses(bare, {2}, ClassSelection::Keep);
    EXPECT_FALSE(bare_twos.hasNormals());
    EXPECT_FALSE(bare_twos.hasColors());
    EXPECT_EQ(bare_twos.vertices, twos.vertices);
}

// A grid of 60 x 60 squares with pseudo-random vertex classes (some without), for the partition.
Mesh labelledGrid() {
    const int n = 61;
    Mesh m;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            m.vertices.push_back({float(x), float(y), 0.f});
            m.normals.push_back({0.f, 0.f, 1.f});
            m.colors.push_back({std::uint8_t(x), std::uint8_t(y), 0});
            const std::uint32_t h = (std::uint32_t(x) * 73856093u) ^ (std::uint32_t(y) * 19349669u);
            m.labels.push_back(h % 7 == 6 ? kNone : ClassId((h >> 3) % 5 + 100));
        }
    for (int y = 0; y + 1 < n; ++y)
        for (int x = 0; x + 1 < n; ++x) {
            const int v = x + n * y;
            m.triangles.push_back({v, v + 1, v + n + 1});
            m.triangles.push_back({v, v + n + 1, v + n});
        }
    return m;
}

using PositionTriangle = std::array<std::tuple<float, float, float>, 3>;

std::vector<PositionTriangle> sortedTriangles(const std::vector<Mesh>& meshes) {
    std::vector<PositionTriangle> all;
    for (const Mesh& m : meshes)
        for (const Vec3i& t : m.triangles) {
            PositionTriangle p;
            for (int c = 0; c < 3; ++c) {
                const Vec3f v = m.vertices[std::size_t(t[c])];
                p[std::size_t(c)] = {v.x, v.y, v.z};
            }
            all.push_back(p);
        }
    std::sort(all.begin(), all.end());
    return all;
}

TEST(MeshLabels, PerClassMeshesPartitionTheMesh) {
    for (const Mesh& m : {handMadeMesh(), labelledGrid()}) {
        const std::vector<ClassId> classes = classesOf(m);
        ASSERT_GE(classes.size(), 4u);
        std::vector<Mesh> parts;
        std::size_t triangles = 0;
        for (const ClassId c : classes) {
            parts.push_back(selectClasses(m, {c}, ClassSelection::Keep));
            EXPECT_FALSE(parts.back().triangles.empty());
            triangles += parts.back().triangles.size();
        }
        EXPECT_EQ(triangles, m.triangles.size()) << "every triangle in exactly one class";
        EXPECT_EQ(sortedTriangles(parts), sortedTriangles({m}));

        // Excluding a class leaves exactly the union of the other classes.
        for (std::size_t i = 0; i < classes.size(); ++i) {
            std::vector<Mesh> others = parts;
            others.erase(others.begin() + std::ptrdiff_t(i));
            const Mesh excluded = selectClasses(m, {classes[i]}, ClassSelection::Exclude);
            EXPECT_EQ(sortedTriangles({excluded}), sortedTriangles(others)) << "class " << classes[i];
        }

        // splitByClass gives the same parts in one pass.
        const std::vector<ClassMesh> split = splitByClass(m);
        ASSERT_EQ(split.size(), classes.size());
        for (std::size_t i = 0; i < split.size(); ++i) {
            EXPECT_EQ(split[i].label, classes[i]);
            expectEqualMeshes(split[i].mesh, parts[i]);
        }
    }
}

TEST(MeshLabels, CloudSelectionByPointLabel) {
    PointCloud cloud;
    cloud.points = {{0.f, 0.f, 0.f}, {1.f, 0.f, 0.f}, {2.f, 0.f, 0.f}, {3.f, 0.f, 0.f}};
    cloud.normals = {{1.f, 0.f, 0.f}, {0.f, 1.f, 0.f}, {0.f, 0.f, 1.f}, {0.f, 0.f, -1.f}};
    cloud.colors = {{1, 1, 1}, {2, 2, 2}, {3, 3, 3}, {4, 4, 4}};
    cloud.labels = {5, kNone, 5, 6};
    EXPECT_EQ(classesOf(cloud), (std::vector<ClassId>{5, 6, kNone}));
    const PointCloud fives = selectClasses(cloud, {5}, ClassSelection::Keep);
    EXPECT_EQ(fives.points, (std::vector<Vec3f>{cloud.points[0], cloud.points[2]}));
    EXPECT_EQ(fives.normals, (std::vector<Vec3f>{cloud.normals[0], cloud.normals[2]}));
    EXPECT_EQ(fives.colors, (std::vector<Vec3u8>{cloud.colors[0], cloud.colors[2]}));
    EXPECT_EQ(fives.labels, (std::vector<ClassId>{5, 5}));
    const PointCloud rest = selectClasses(cloud, {5}, ClassSelection::Exclude);
    EXPECT_EQ(rest.points, (std::vector<Vec3f>{cloud.points[1], cloud.points[3]}));
    EXPECT_EQ(rest.labels, (std::vector<ClassId>{kNone, 6}));
    EXPECT_EQ(rest.colors, (std::vector<Vec3u8>{cloud.colors[1], cloud.colors[3]}));
}

TEST(MeshLabels, UnlabelledOrInconsistentInputIsRefused) {
    Mesh unlabelled = handMadeMesh();
    unlabelled.labels.clear();
    EXPECT_THROW(triangleClass(unlabelled, 0), Error);
    EXPECT_THROW(classesOf(unlabelled), Error);
    EXPECT_THROW(selectClasses(unlabelled, {1}, ClassSelection::Keep), Error);
    EXPECT_THROW(splitByClass(unlabelled), Error);
    try {
        classesOf(unlabelled);
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("no labels"), std::string::npos) << e.what();
    }
    Mesh short_labels = handMadeMesh();
    short_labels.labels.pop_back();
    EXPECT_THROW(selectClasses(short_labels, {1}, ClassSelection::Keep), Error);
    Mesh bad_triangle = handMadeMesh();
    bad_triangle.triangles.push_back({0, 1, 8});
    EXPECT_THROW(selectClasses(bad_triangle, {1}, ClassSelection::Keep), Error);
    Mesh bad_colors = handMadeMesh();
    bad_colors.colors.pop_back();
    EXPECT_THROW(splitByClass(bad_colors), Error);

    PointCloud cloud;
    cloud.points = {{0.f, 0.f, 0.f}};
    EXPECT_THROW(selectClasses(cloud, {1}, ClassSelection::Keep), Error);
    EXPECT_THROW(classesOf(cloud), Error);

    // Empty input is not unlabelled: it just has no classes.
    EXPECT_TRUE(classesOf(Mesh()).empty());
    EXPECT_TRUE(splitByClass(Mesh()).empty());
    EXPECT_TRUE(selectClasses(PointCloud(), {1}, ClassSelection::Exclude).empty());
}

}  // namespace
}  // namespace voxfuse
