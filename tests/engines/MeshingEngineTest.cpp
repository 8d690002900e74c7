// Marching cubes: the generated case table is consistent, and meshes of analytic, fused and random
// SDFs are closed, consistently wound, free of duplicate vertices, on the surface, and the same for the
// dense and the hash index.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "SyntheticViews.h"
#include "voxfuse/core/CpuThreads.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/AllocationEngine.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/engines/MeshingEngine.h"
#include "voxfuse/objects/Voxel.h"
#include "voxfuse/shared/MarchingCubes.h"
#include "voxfuse/shared/VoxelAccess.h"

namespace voxfuse {
namespace {

// ================================ The case table ================================

using DirectedEdge = std::pair<int, int>;  // two cube edges joined by a triangle side

std::vector<DirectedEdge> triangleSides(int cube) {
    std::vector<DirectedEdge> sides;
    const MarchingCubesTable& t = kMarchingCubesTable;
    for (int k = 0; k < t.triangle_count[cube]; ++k) {
        const std::int8_t* e = t.triangle_edges[cube] + 3 * k;
        sides.push_back({e[0], e[1]});
        sides.push_back({e[1], e[2]});
        sides.push_back({e[2], e[0]});
    }
    return sides;
}

// Sides without a reverse in the same cell: where the cell's surface meets the cube's faces.
std::multiset<DirectedEdge> boundarySides(int cube) {
    const std::vector<DirectedEdge> sides = triangleSides(cube);
    std::multiset<DirectedEdge> all(sides.begin(), sides.end()), boundary;
    for (const DirectedEdge& s : sides)
        if (!all.count({s.second, s.first})) boundary.insert(s);
    return boundary;
}

// Whether cube edge `edge` lies on face `face` (axis face / 2 at coordinate face % 2).
bool edgeOnFace(int edge, int face) {
    const int axis = face / 2, side = face % 2;
    if (cubeEdgeAxis(edge) == axis) return false;
    return ((cubeEdgeStartCorner(edge) >> axis) & 1) == side;
}

TEST(MarchingCubesTable, CubeTopologyIsConsistent) {
    for (int e = 0; e < kCubeEdges; ++e) {
        const int a = cubeEdgeStartCorner(e), b = cubeEdgeEndCorner(e);
        EXPECT_EQ(a ^ b, 1 << cubeEdgeAxis(e));
        EXPECT_EQ((a >> cubeEdgeAxis(e)) & 1, 0);
        EXPECT_EQ(cubeEdgeBetween(a, b), e);
        EXPECT_EQ(cubeEdgeBetween(b, a), e);
    }
}

TEST(MarchingCubesTable, CutEdgesAreTheSignChangesAndAllAreUsed) {
    for (int cube = 0; cube < 256; ++cube) {
        int expected = 0, used = 0;
        for (int e = 0; e < kCubeEdges; ++e)
            if (((cube >> cubeEdgeStartCorner(e)) & 1) != ((cube >> cubeEdgeEndCorner(e)) & 1)) expected |= 1 << e;
        for (const DirectedEdge& s : triangleSides(cube)) used |= (1 << s.first) | (1 << s.second);
        EXPECT_EQ(kMarchingCubesTable.cut_edges[cube], expected) << "case " << cube;
        EXPECT_EQ(used, expected) << "case " << cube << ": triangles must use exactly the cut edges";
        EXPECT_LE(kMarchingCubesTable.triangle_count[cube], kMaxCellTriangles);
    }
    EXPECT_EQ(kMarchingCubesTable.triangle_count[0], 0);
    EXPECT_EQ(kMarchingCubesTable.triangle_count[255], 0);
}

// Inside a cell every triangle side is shared by two triangles, wound oppositely; the remaining sides
// lie on the cube's faces and form closed loops through the cut edges.
TEST(MarchingCubesTable, EveryCaseClosesAroundItsCutEdges) {
    for (int cube = 0; cube < 256; ++cube) {
        const std::vector<DirectedEdge> sides = triangleSides(cube);
        std::multiset<DirectedEdge> all(sides.begin(), sides.end());
        for (const DirectedEdge& s : all) {
            EXPECT_EQ(all.count(s), 1u) << "case " << cube << ": a side used twice in one direction";
            bool on_common_face = false;
            for (int f = 0; f < 6; ++f)
                on_common_face = on_common_face || (edgeOnFace(s.first, f) && edgeOnFace(s.second, f));
            // An inner side in a face could meet the neighbouring cell's surface there.
            if (all.count({s.second, s.first})) {
                EXPECT_FALSE(on_common_face) << "case " << cube << ": an inner side lies in a face";
            }
        }
        std::map<int, int> out_degree, in_degree;
        for (const DirectedEdge& s : boundarySides(cube)) {
            bool on_common_face = false;
            for (int f = 0; f < 6; ++f)
                on_common_face = on_common_face || (edgeOnFace(s.first, f) && edgeOnFace(s.second, f));
            EXPECT_TRUE(on_common_face) << "case " << cube << ": an open side crosses the cell";
            ++out_degree[s.first];
            ++in_degree[s.second];
        }
        for (int e = 0; e < kCubeEdges; ++e) {
            if (!((kMarchingCubesTable.cut_edges[cube] >> e) & 1)) continue;
            EXPECT_EQ(out_degree[e], 1) << "case " << cube << " edge " << e;
            EXPECT_EQ(in_degree[e], 1) << "case " << cube << " edge " << e;
        }
    }
}

// Two cells sharing a face cut it with the same segments, wound oppositely, whatever their other
// corners: this is what makes meshes closed.
TEST(MarchingCubesTable, NeighbouringCellsCutTheirSharedFaceAlike) {
    for (int axis = 0; axis < 3; ++axis) {
        const int bit = 1 << axis;
        // Cell A's face at +axis is cell B's face at -axis; corner k of A (bit set) is corner k ^ bit of B.
        auto toB = [bit](int edge_of_a) {
            return cubeEdgeBetween(cubeEdgeStartCorner(edge_of_a) ^ bit, cubeEdgeEndCorner(edge_of_a) ^ bit);
        };
        for (int a = 0; a < 256; ++a)
            for (int b = 0; b < 256; ++b) {
                bool same_face = true;
                for (int k = 0; k < 8; ++k)
                    if (k & bit) same_face = same_face && (((a >> k) & 1) == ((b >> (k ^ bit)) & 1));
                if (!same_face) continue;
                std::multiset<DirectedEdge> from_a, from_b;
                for (const DirectedEdge& s : boundarySides(a))
                    if (edgeOnFace(s.first, 2 * axis + 1) && edgeOnFace(s.second, 2 * axis + 1))
                        from_a.insert({toB(s.second), toB(s.first)});
                for (const DirectedEdge& s : boundarySides(b))
                    if (edgeOnFace(s.first, 2 * axis) && edgeOnFace(s.second, 2 * axis)) from_b.insert(s);
                ASSERT_EQ(from_a, from_b) << "cells " << a << " and " << b << " along axis " << axis;
            }
    }
}

// With vertices at the edge midpoints, every triangle faces from its inside corners to its outside ones.
TEST(MarchingCubesTable, TrianglesFaceTheOutsideCorners) {
    auto midpoint = [](int e) {
        return (toFloat(cubeCornerOffset(cubeEdgeStartCorner(e))) + toFloat(cubeCornerOffset(cubeEdgeEndCorner(e)))) *
               0.5f;
    };
    for (int cube = 0; cube < 256; ++cube)
        for (int k = 0; k < kMarchingCubesTable.triangle_count[cube]; ++k) {
            const std::int8_t* e = kMarchingCubesTable.triangle_edges[cube] + 3 * k;
            const Vec3f n = cross(midpoint(e[1]) - midpoint(e[0]), midpoint(e[2]) - midpoint(e[0]));
            Vec3f inside_to_outside{0.f, 0.f, 0.f};
            for (int j = 0; j < 3; ++j) {
                const bool start_inside = (cube >> cubeEdgeStartCorner(e[j])) & 1;
                Vec3f axis{0.f, 0.f, 0.f};
                axis[cubeEdgeAxis(e[j])] = start_inside ? 1.f : -1.f;
                inside_to_outside += axis;
            }
            EXPECT_GT(dot(n, inside_to_outside), 0.f) << "case " << cube << " triangle " << k;
        }
}

TEST(MarchingCubesCell, CrossingsStayInsideTheEdge) {
    float corners[8] = {-1, 1, 1, 1, 1, 1, 1, 1};
    EXPECT_EQ(cubeCase(corners), 1);
    corners[0] = 0.f;  // zero is outside
    EXPECT_EQ(cubeCase(corners), 0);
    EXPECT_FLOAT_EQ(edgeCrossing(-0.25f, 0.75f), 0.25f);
    EXPECT_FLOAT_EQ(edgeCrossing(0.5f, -0.5f), 0.5f);
    EXPECT_GT(edgeCrossing(-1.f, 0.f), 0.99f);
    EXPECT_LT(edgeCrossing(-1.f, 0.f), 1.f);
    EXPECT_FLOAT_EQ(sdfDifference(0.f, true, 1.f, 4.f, true), 2.f);
    EXPECT_FLOAT_EQ(sdfDifference(0.f, false, 1.f, 4.f, true), 3.f);
    EXPECT_FLOAT_EQ(sdfDifference(0.f, true, 1.f, 4.f, false), 1.f);
    EXPECT_FLOAT_EQ(sdfDifference(0.f, false, 1.f, 4.f, false), 0.f);
}

// ================================ Mesh checks ================================

struct Topology {
    std::size_t edges = 0;
    int open_edges = 0;         // used by one triangle
    int overused_edges = 0;     // used by more than two
    int misoriented_edges = 0;  // used twice in the same direction
    int degenerate_triangles = 0;
    long long eulerCharacteristic(const Mesh& m) const {
        return (long long)m.vertices.size() - (long long)edges + (long long)m.triangles.size();
    }
    bool closedAndOriented() const { return open_edges == 0 && overused_edges == 0 && misoriented_edges == 0; }
};

Topology topologyOf(const Mesh& mesh) {
    std::map<std::pair<int, int>, std::pair<int, int>> uses;  // undirected side -> (uses, uses from min to max)
    Topology t;
    for (const Vec3i& tri : mesh.triangles) {
        if (tri.x == tri.y || tri.y == tri.z || tri.z == tri.x) ++t.degenerate_triangles;
        for (int k = 0; k < 3; ++k) {
            const int a = tri[k], b = tri[(k + 1) % 3];
            auto& u = uses[{std::min(a, b), std::max(a, b)}];
            ++u.first;
            u.second += a < b;
        }
    }
    t.edges = uses.size();
    for (const auto& [side, u] : uses) {
        if (u.first == 1) ++t.open_edges;
        if (u.first > 2) ++t.overused_edges;
        if (u.first == 2 && u.second != 1) ++t.misoriented_edges;
    }
    return t;
}

bool lexicographicLess(const Vec3f& a, const Vec3f& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); }

int duplicatePositions(const Mesh& mesh) {
    std::vector<Vec3f> v = mesh.vertices;
    std::sort(v.begin(), v.end(), lexicographicLess);
    int duplicates = 0;
    for (std::size_t i = 1; i < v.size(); ++i) duplicates += v[i] == v[i - 1];
    return duplicates;
}

// Every structural property a mesh must have, whatever the scene.
void expectWellFormed(const Mesh& mesh, bool has_colors, bool has_labels = false) {
    ASSERT_EQ(mesh.normals.size(), mesh.vertices.size());
    EXPECT_EQ(mesh.colors.size(), has_colors ? mesh.vertices.size() : 0u);
    EXPECT_EQ(mesh.labels.size(), has_labels ? mesh.vertices.size() : 0u);
    for (const Vec3i& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) ASSERT_TRUE(t[k] >= 0 && t[k] < int(mesh.vertices.size()));
    for (const Vec3f& n : mesh.normals) EXPECT_NEAR(length(n), 1.f, 1e-4f);
    EXPECT_EQ(duplicatePositions(mesh), 0) << "vertices must be shared, not repeated";
    std::vector<int> uses(mesh.vertices.size(), 0);
    for (const Vec3i& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) ++uses[std::size_t(t[k])];
    EXPECT_EQ(std::count(uses.begin(), uses.end(), 0), 0) << "every vertex belongs to a triangle";
}

Vec3f faceNormal(const Mesh& m, const Vec3i& t) {
    return normalize(cross(m.vertices[std::size_t(t.y)] - m.vertices[std::size_t(t.x)],
                           m.vertices[std::size_t(t.z)] - m.vertices[std::size_t(t.x)]));
}

// ================================ Scenes ================================

constexpr float kVoxel = 0.01f;

SceneParams testParams() {
    SceneParams p;
    p.voxel_size_m = kVoxel;
    p.mu_m = 0.04f;
    p.view_frustum_max_m = 2.5f;
    return p;
}

VoxelBlockHashSettings smallHash() {
    VoxelBlockHashSettings s;
    s.bucket_count = 0x8000;
    s.excess_entry_count = 0x2000;
    s.max_block_count = 0x8000;
    s.blocks_per_growth = 512;
    return s;
}

// What a filled voxel holds: its SDF (in units of mu, clamped to [-1, 1]), whether it was observed, and
// its class for voxel types with labels (kNoLabel: w_label = 0).
struct VoxelValue {
    float sdf = 1.f;
    bool observed = false;
    ClassId label = kNoLabel;
};
using Field = std::function<VoxelValue(Vec3i voxel)>;

template <class TVoxel>
TVoxel makeVoxel(const VoxelValue& value, Vec3i p) {
    TVoxel v = TVoxel::initial();
    if (!value.observed) return v;
    v.sdf = TVoxel::sdfFromFloat(clampValue(value.sdf, -1.f, 1.f));
    v.w_depth = 1;
    if constexpr (TVoxel::hasColor) {
        v.w_color = 1;
        v.clr = Vec3u8{std::uint8_t(p.x & 255), std::uint8_t(p.y & 255), std::uint8_t(p.z & 255)};
    }
    if constexpr (TVoxel::hasLabel) {
        v.w_label = value.label == kNoLabel ? 0 : 1;
        v.label = value.label;
    }
    return v;
}

template <class TVoxel>
void fillDense(Scene<TVoxel, PlainVoxelArray>& scene, const Field& field) {
    const PlainVoxelArray::Data idx = scene.index().data();
    TVoxel* voxels = scene.voxels().host();
    for (int z = 0; z < idx.size.z; ++z)
        for (int y = 0; y < idx.size.y; ++y)
            for (int x = 0; x < idx.size.x; ++x) {
                const Vec3i p = Vec3i{x, y, z} + idx.offset;
                voxels[x + idx.size.x * (y + idx.size.y * z)] = makeVoxel<TVoxel>(field(p), p);
            }
}

// Allocates every block of [voxel_lo, voxel_hi) (voxel coordinates, rounded out to blocks) and fills it.
template <class TVoxel>
void fillHash(Scene<TVoxel, VoxelBlockHash>& scene, Vec3i voxel_lo, Vec3i voxel_hi, const Field& field) {
    const Vec3i lo = blockOfVoxel(voxel_lo), hi = blockOfVoxel(voxel_hi - Vec3i{1, 1, 1});
    scene.reserveVoxelBlocks((hi.x - lo.x + 1) * (hi.y - lo.y + 1) * (hi.z - lo.z + 1));
    for (int bz = lo.z; bz <= hi.z; ++bz)
        for (int by = lo.y; by <= hi.y; ++by)
            for (int bx = lo.x; bx <= hi.x; ++bx) {
                int entry = -1;
                ASSERT_EQ(scene.index().insert({bx, by, bz}, &entry), VoxelBlockHash::InsertResult::Inserted);
                TVoxel* block = scene.voxels().host() + std::size_t(scene.index().entry(entry).ptr) * kBlockVoxelCount;
                for (int i = 0; i < kBlockVoxelCount; ++i) {
                    const Vec3i p = Vec3i{bx, by, bz} * kBlockSide + Vec3i{i & 7, (i >> 3) & 7, i >> 6};
                    block[i] = makeVoxel<TVoxel>(field(p), p);
                }
            }
}

template <class TVoxel, class TIndex>
Mesh meshOf(const Scene<TVoxel, TIndex>& scene) {
    Mesh mesh;
    makeMeshingEngine<TVoxel, TIndex>(Device::CPU)->extractMesh(scene, mesh);
    return mesh;
}

// Exact truncated SDFs, positive outside; voxel centres at p * kVoxel.
constexpr float kRadius = 0.25f;
const Vec3f kSphereCentre{0.013f, -0.021f, 0.007f};  // off the grid: no voxel exactly on the surface

VoxelValue sphereSdf(Vec3i p) {
    return {(length(toFloat(p) * kVoxel - kSphereCentre) - kRadius) / testParams().mu_m, true};
}

const Vec3f kBoxCentre{0.0034f, 0.0121f, -0.0057f};
const Vec3f kBoxHalf{0.2f, 0.13f, 0.09f};

float boxDistance(Vec3f p) {
    const Vec3f d{std::fabs(p.x - kBoxCentre.x) - kBoxHalf.x, std::fabs(p.y - kBoxCentre.y) - kBoxHalf.y,
                  std::fabs(p.z - kBoxCentre.z) - kBoxHalf.z};
    const Vec3f outside{std::max(d.x, 0.f), std::max(d.y, 0.f), std::max(d.z, 0.f)};
    return length(outside) + std::min(std::max(d.x, std::max(d.y, d.z)), 0.f);
}

VoxelValue boxSdf(Vec3i p) { return {boxDistance(toFloat(p) * kVoxel) / testParams().mu_m, true}; }

// ================================ Analytic surfaces ================================

template <class TVoxel>
class MeshingEngineTest : public ::testing::Test {};
using VoxelTypes = ::testing::Types<VoxelS, VoxelF, VoxelSRgb, VoxelFRgb, VoxelSLabel, VoxelSRgbLabel>;
TYPED_TEST_SUITE(MeshingEngineTest, VoxelTypes);

// Vertices within max_error_voxels of the sphere; 99% of the normals within normal_error_deg of radial.
void expectClosedSphere(const Mesh& mesh, bool has_colors, float max_error_voxels, float normal_error_deg,
                        bool has_labels = false) {
    expectWellFormed(mesh, has_colors, has_labels);
    ASSERT_GT(mesh.triangles.size(), 5000u);
    const Topology t = topologyOf(mesh);
    EXPECT_TRUE(t.closedAndOriented()) << t.open_edges << " open, " << t.overused_edges << " overused, "
                                       << t.misoriented_edges << " misoriented edges";
    EXPECT_EQ(t.degenerate_triangles, 0);
    EXPECT_EQ(t.eulerCharacteristic(mesh), 2) << "one closed surface of genus 0";
    float max_error = 0.f;
    int normals_off = 0;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        const Vec3f radial = mesh.vertices[i] - kSphereCentre;
        max_error = std::max(max_error, std::fabs(length(radial) - kRadius));
        normals_off += dot(mesh.normals[i], normalize(radial)) < std::cos(normal_error_deg * 3.14159265f / 180.f);
    }
    EXPECT_LT(max_error, max_error_voxels * kVoxel) << "vertices off the analytic sphere";
    EXPECT_LE(normals_off, int(mesh.vertices.size() / 100)) << "vertex normals (SDF gradient) should be radial";
    for (const Vec3i& tri : mesh.triangles)
        ASSERT_GT(dot(faceNormal(mesh, tri), normalize(mesh.vertices[std::size_t(tri.x)] - kSphereCentre)), 0.5f)
            << "triangles must face outwards";
}

TYPED_TEST(MeshingEngineTest, AnalyticSphereIsClosedAndWithinHalfAVoxel) {
    using TVoxel = TypeParam;
    Scene<TVoxel, PlainVoxelArray> dense(testParams(), PlainVoxelArray({-30, -30, -30}, {60, 60, 60}), Device::CPU);
    fillDense(dense, sphereSdf);
    const Mesh dense_mesh = meshOf(dense);
    expectClosedSphere(dense_mesh, TVoxel::hasColor, 0.5f, 1.f, TVoxel::hasLabel);

    Scene<TVoxel, VoxelBlockHash> hash(testParams(), VoxelBlockHash(smallHash()), Device::CPU);
    fillHash(hash, {-30, -30, -30}, {30, 30, 30}, sphereSdf);
    const Mesh hash_mesh = meshOf(hash);
    expectClosedSphere(hash_mesh, TVoxel::hasColor, 0.5f, 1.f, TVoxel::hasLabel);
    EXPECT_EQ(hash_mesh.vertices.size(), dense_mesh.vertices.size());
    EXPECT_EQ(hash_mesh.triangles.size(), dense_mesh.triangles.size());

    // Voxel p has colour p & 255 per channel, so the colour interpolated to a vertex is its position in
    // voxels, rounded (away from where the colour wraps from 255 to 0).
    if constexpr (TVoxel::hasColor) {
        int checked = 0, wrong = 0;
        for (std::size_t i = 0; i < hash_mesh.vertices.size(); ++i) {
            const Vec3f g = hash_mesh.vertices[i] / kVoxel;
            if (g.x < 0.5f && g.x > -1.5f) continue;
            if (g.y < 0.5f && g.y > -1.5f) continue;
            if (g.z < 0.5f && g.z > -1.5f) continue;
            ++checked;
            for (int a = 0; a < 3; ++a)
                wrong += hash_mesh.colors[i][a] != std::uint8_t(int(std::floor(g[a] + 0.5f)) & 255);
        }
        EXPECT_GT(checked, 1000);
        EXPECT_EQ(wrong, 0) << "vertex colours interpolate the voxel colours along the edge";
    }
    // No voxel has a class (w_label = 0): no vertex has one.
    if constexpr (TVoxel::hasLabel) {
        EXPECT_EQ(std::count(hash_mesh.labels.begin(), hash_mesh.labels.end(), kNoLabel),
                  std::ptrdiff_t(hash_mesh.labels.size()));
    }
}

TEST(MeshingEngine, AnalyticBoxIsClosedAndWithinHalfAVoxel) {
    for (bool use_hash : {false, true}) {
        Mesh mesh;
        if (use_hash) {
            Scene<VoxelS, VoxelBlockHash> scene(testParams(), VoxelBlockHash(smallHash()), Device::CPU);
            fillHash(scene, {-28, -22, -17}, {28, 22, 17}, boxSdf);
            mesh = meshOf(scene);
        } else {
            Scene<VoxelF, PlainVoxelArray> scene(testParams(), PlainVoxelArray({-28, -22, -17}, {56, 44, 34}),
                                                 Device::CPU);
            fillDense(scene, boxSdf);
            mesh = meshOf(scene);
        }
        SCOPED_TRACE(use_hash ? "hash" : "dense");
        expectWellFormed(mesh, false);
        const Topology t = topologyOf(mesh);
        EXPECT_TRUE(t.closedAndOriented())
            << t.open_edges << " open, " << t.overused_edges << " overused, " << t.misoriented_edges;
        EXPECT_EQ(t.eulerCharacteristic(mesh), 2);
        float max_error = 0.f;
        for (const Vec3f& v : mesh.vertices) max_error = std::max(max_error, std::fabs(boxDistance(v)));
        EXPECT_LT(max_error, 0.5f * kVoxel);
        // Faces point out: on each flat side (away from the box's edges) the normals are the side's axis.
        int flat = 0, aligned = 0;
        for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
            const Vec3f d = mesh.vertices[i] - kBoxCentre;
            for (int a = 0; a < 3; ++a) {
                const int b = (a + 1) % 3, c = (a + 2) % 3;
                if (std::fabs(std::fabs(d[a]) - kBoxHalf[a]) > 0.01f || std::fabs(d[b]) > kBoxHalf[b] - 0.03f ||
                    std::fabs(d[c]) > kBoxHalf[c] - 0.03f)
                    continue;
                ++flat;
                aligned += mesh.normals[i][a] * (d[a] > 0.f ? 1.f : -1.f) > 0.999f;
            }
        }
        EXPECT_GT(flat, 1000);
        EXPECT_EQ(aligned, flat);
    }
}

// ================================ Classes ================================

constexpr ClassId kLeftClass = 3, kRightClass = 7;

VoxelValue sphereWithClassedHalves(Vec3i p) {
    VoxelValue v = sphereSdf(p);
    v.label = p.x < 0 ? kLeftClass : kRightClass;
    return v;
}

// The same halves, but every fifth voxel along x + 2y + 3z has no class (two neighbours never both
// lack one), nor has any voxel above z = 15.
ClassId classWithGaps(Vec3i p) {
    if (p.z > 15 || ((p.x + 2 * p.y + 3 * p.z) % 5 + 5) % 5 == 0) return kNoLabel;
    return p.x < 0 ? kLeftClass : kRightClass;
}

VoxelValue sphereWithClassGaps(Vec3i p) {
    VoxelValue v = sphereSdf(p);
    v.label = classWithGaps(p);
    return v;
}

// Position -> class, to compare outputs whose vertices come in different orders.
std::map<std::tuple<float, float, float>, ClassId> classByPosition(const std::vector<Vec3f>& points,
                                                                   const std::vector<ClassId>& labels) {
    std::map<std::tuple<float, float, float>, ClassId> classes;
    for (std::size_t i = 0; i < points.size(); ++i) classes[{points[i].x, points[i].y, points[i].z}] = labels[i];
    return classes;
}

TEST(MeshingEngine, SphereHalvesKeepTheirVoxelsClasses) {
    Scene<VoxelSLabel, PlainVoxelArray> dense(testParams(), PlainVoxelArray({-30, -30, -30}, {60, 60, 60}),
                                              Device::CPU);
    fillDense(dense, sphereWithClassedHalves);
    Scene<VoxelSLabel, VoxelBlockHash> hash(testParams(), VoxelBlockHash(smallHash()), Device::CPU);
    fillHash(hash, {-30, -30, -30}, {30, 30, 30}, sphereWithClassedHalves);
    const Mesh dense_mesh = meshOf(dense), hash_mesh = meshOf(hash);
    expectClosedSphere(dense_mesh, false, 0.5f, 1.f, true);
    expectWellFormed(hash_mesh, false, true);

    int checked = 0, wrong = 0;
    for (std::size_t i = 0; i < hash_mesh.vertices.size(); ++i) {
        const float x_voxels = hash_mesh.vertices[i].x / kVoxel;
        if (std::fabs(x_voxels) <= 1.f) continue;
        ++checked;
        wrong += hash_mesh.labels[i] != (x_voxels < 0.f ? kLeftClass : kRightClass);
    }
    EXPECT_GT(checked, 3000);
    EXPECT_EQ(wrong, 0) << "vertices away from x = 0 have the class of their side";
    EXPECT_EQ(std::count(hash_mesh.labels.begin(), hash_mesh.labels.end(), kNoLabel), 0);
    EXPECT_TRUE(classByPosition(dense_mesh.vertices, dense_mesh.labels) ==
                classByPosition(hash_mesh.vertices, hash_mesh.labels))
        << "the dense and the hash mesh give every vertex the same class";

    // The point cloud is the mesh's vertices, classes included, in the same order.
    PointCloud dense_cloud, hash_cloud;
    makeMeshingEngine<VoxelSLabel, PlainVoxelArray>(Device::CPU)->extractPointCloud(dense, dense_cloud);
    makeMeshingEngine<VoxelSLabel, VoxelBlockHash>(Device::CPU)->extractPointCloud(hash, hash_cloud);
    EXPECT_EQ(dense_cloud.points, dense_mesh.vertices);
    EXPECT_EQ(dense_cloud.labels, dense_mesh.labels);
    EXPECT_EQ(hash_cloud.points, hash_mesh.vertices);
    EXPECT_EQ(hash_cloud.labels, hash_mesh.labels);
}

// A vertex takes the class of the edge end nearer to it, or the other end's where that one has none.
TEST(MeshingEngine, VertexClassIsTheNearerEndsElseTheFarther) {
    Scene<VoxelSRgbLabel, VoxelBlockHash> hash(testParams(), VoxelBlockHash(smallHash()), Device::CPU);
    fillHash(hash, {-30, -30, -30}, {30, 30, 30}, sphereWithClassGaps);
    const Mesh mesh = meshOf(hash);
    expectClosedSphere(mesh, true, 0.5f, 1.f, true);
    int checked = 0, from_farther = 0, without_class = 0, wrong = 0;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        // The vertex's edge: the axis along which it is off the grid (by 1e-3 voxel at least).
        const Vec3f g = mesh.vertices[i] / kVoxel;
        int axis = 0;
        for (int a = 1; a < 3; ++a)
            if (std::fabs(g[a] - std::round(g[a])) > std::fabs(g[axis] - std::round(g[axis]))) axis = a;
        Vec3i start{int(std::lround(g.x)), int(std::lround(g.y)), int(std::lround(g.z))};
        start[axis] = int(std::floor(g[axis]));
        const float t = g[axis] - float(start[axis]);
        if (std::fabs(t - 0.5f) < 1e-3f) continue;  // too close to call after rounding
        Vec3i end = start;
        ++end[axis];
        const ClassId nearer = classWithGaps(t < 0.5f ? start : end), farther = classWithGaps(t < 0.5f ? end : start);
        const ClassId expected = nearer != kNoLabel ? nearer : farther;
        ++checked;
        from_farther += nearer == kNoLabel && farther != kNoLabel;
        without_class += expected == kNoLabel;
        wrong += mesh.labels[i] != expected;
    }
    EXPECT_GT(checked, int(mesh.vertices.size()) * 9 / 10);
    EXPECT_GT(from_farther, 300) << "the test must reach the fallback to the farther end";
    EXPECT_GT(without_class, 300) << "and vertices without any class";
    EXPECT_EQ(wrong, 0);
}

// ================================ Fused surfaces ================================

// Cameras on a sphere of radius `distance` around `target`, spread by the golden angle.
std::vector<Mat4f> camerasAllAround(const Eigen::Vector3f& target, float distance, int count) {
    std::vector<Mat4f> poses;
    for (int i = 0; i < count; ++i) {
        const float z = 1.f - 2.f * (float(i) + 0.5f) / float(count);
        const float r = std::sqrt(1.f - z * z), phi = 2.39996323f * float(i);
        poses.push_back(
            test::lookAt(target + distance * Eigen::Vector3f(r * std::cos(phi), r * std::sin(phi), z), target));
    }
    return poses;
}

template <class TVoxel, class TIndex>
void fuse(Scene<TVoxel, TIndex>& scene, const synth::SyntheticScene& world, const std::vector<Mat4f>& poses) {
    auto allocation = makeAllocationEngine<TVoxel, TIndex>(Device::CPU);
    auto integration = makeIntegrationEngine<TVoxel, TIndex>(Device::CPU);
    const Intrinsics intr = test::kinectIntrinsics(160, 120);
    for (const Mat4f& pose : poses) {
        const View view = test::renderView(world, intr, pose);
        allocation->allocate(scene, view, pose);
        integration->integrate(scene, view, pose);
    }
}

TEST(MeshingEngine, FusedSphereSeenFromAllAroundIsClosed) {
    const Eigen::Vector3f centre(kSphereCentre.x, kSphereCentre.y, kSphereCentre.z);
    const synth::SyntheticScene world = synth::SyntheticScene::singleSphere(centre, kRadius);
    const std::vector<Mat4f> poses = camerasAllAround(centre, 0.9f, 30);
    Scene<VoxelFRgb, PlainVoxelArray> dense(testParams(), PlainVoxelArray({-40, -40, -40}, {80, 80, 80}), Device::CPU);
    Scene<VoxelFRgb, VoxelBlockHash> hash(testParams(), VoxelBlockHash(smallHash()), Device::CPU);
    fuse(dense, world, poses);
    fuse(hash, world, poses);
    for (const Mesh& mesh : {meshOf(dense), meshOf(hash)}) {
        // The fused TSDF is an average of projective distances, not a Euclidean distance: its gradient
        // is a few degrees off the true normal (median 4 degrees here, face normals do no better).
        expectClosedSphere(mesh, true, 0.5f, 15.f);
        int uncoloured = 0;
        for (const Vec3u8& c : mesh.colors) uncoloured += c.x == 0 && c.y == 0 && c.z == 0;
        EXPECT_EQ(uncoloured, 0) << "every vertex of a surface seen in colour has a colour";
    }
}

// A box and a sphere without a floor, inside the dense extent; the cameras see nothing behind them.
synth::SyntheticScene boxAndSphereInTheAir() {
    synth::SyntheticScene world;
    world.addBox({-0.15f, 0.05f, 0.f},
                 Eigen::Quaternionf(Eigen::AngleAxisf(0.4f, Eigen::Vector3f(0.2f, 0.3f, 1.f).normalized())),
                 {0.12f, 0.09f, 0.07f});
    world.addSphere({0.2f, -0.05f, 0.05f}, 0.11f);
    return world;
}

// Sorted vertices and triangles as sorted position triples, for comparing meshes made in another order.
struct CanonicalMesh {
    std::vector<Vec3f> vertices;
    std::vector<std::array<int, 3>> triangles;  // indices into the sorted vertices, rotated to start at the least
};

CanonicalMesh canonical(const Mesh& mesh) {
    std::vector<int> order(mesh.vertices.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = int(i);
    std::sort(order.begin(), order.end(), [&](int a, int b) {
        return lexicographicLess(mesh.vertices[std::size_t(a)], mesh.vertices[std::size_t(b)]);
    });
    std::vector<int> rank(order.size());
    CanonicalMesh c;
    for (std::size_t r = 0; r < order.size(); ++r) {
        rank[std::size_t(order[r])] = int(r);
        c.vertices.push_back(mesh.vertices[std::size_t(order[r])]);
    }
    for (const Vec3i& t : mesh.triangles) {
        std::array<int, 3> tri{rank[std::size_t(t.x)], rank[std::size_t(t.y)], rank[std::size_t(t.z)]};
        std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
        c.triangles.push_back(tri);
    }
    std::sort(c.triangles.begin(), c.triangles.end());
    return c;
}

void expectSameMesh(const Mesh& a, const Mesh& b, float tolerance_m) {
    const CanonicalMesh ca = canonical(a), cb = canonical(b);
    ASSERT_EQ(ca.vertices.size(), cb.vertices.size());
    float max_distance = 0.f;
    for (std::size_t i = 0; i < ca.vertices.size(); ++i)
        max_distance = std::max(max_distance, length(ca.vertices[i] - cb.vertices[i]));
    EXPECT_LE(max_distance, tolerance_m);
    ASSERT_EQ(ca.triangles.size(), cb.triangles.size());
    EXPECT_TRUE(ca.triangles == cb.triangles) << "same triangles over the same vertices";
}

// The dense and the hash index fuse the frames into the same voxels near the surface (see
// HashDenseParityTest), so the meshes are the same.
TEST(MeshingEngine, DenseAndHashMeshesOfTheSameFramesMatch) {
    const synth::SyntheticScene world = boxAndSphereInTheAir();
    std::vector<Mat4f> poses;
    for (int k = 0; k < 6; ++k) {
        const float a = 0.5f * float(k);
        poses.push_back(
            test::lookAt({0.9f * std::cos(a), 0.9f * std::sin(a), 0.35f - 0.1f * float(k)}, {0.f, 0.f, 0.02f}));
    }
    Scene<VoxelSRgb, PlainVoxelArray> dense(testParams(), PlainVoxelArray({-64, -64, -64}, {128, 128, 128}),
                                            Device::CPU);
    Scene<VoxelSRgb, VoxelBlockHash> hash(testParams(), VoxelBlockHash(smallHash()), Device::CPU);
    fuse(dense, world, poses);
    fuse(hash, world, poses);
    const Mesh dense_mesh = meshOf(dense), hash_mesh = meshOf(hash);
    ASSERT_GT(dense_mesh.triangles.size(), 5000u);
    expectWellFormed(dense_mesh, true);
    expectWellFormed(hash_mesh, true);
    expectSameMesh(dense_mesh, hash_mesh, 1e-5f);
}

// ================================ Random fields, borders, threads ================================

// Random SDF values (every sign pattern of a cell occurs) inside a box of observed +1: the surface is
// closed, and crosses hash block borders everywhere.
VoxelValue randomSdf(Vec3i p) {
    const Vec3i lo{-13, -11, -9}, hi{12, 14, 10};  // strictly inside, off the block grid
    if (p.x <= lo.x || p.y <= lo.y || p.z <= lo.z || p.x >= hi.x || p.y >= hi.y || p.z >= hi.z) return {1.f, true};
    std::uint32_t h = std::uint32_t(p.x * 73856093) ^ std::uint32_t(p.y * 19349669) ^ std::uint32_t(p.z * 83492791);
    h = (h ^ (h >> 13)) * 0x5bd1e995u;
    h ^= h >> 15;
    return {float(h % 2001u) / 1000.f - 1.f + 0.0005f, true};  // never exactly 0
}

TEST(MeshingEngine, RandomFieldGivesAClosedOrientedSurfaceAcrossBlockBorders) {
    Scene<VoxelF, PlainVoxelArray> dense(testParams(), PlainVoxelArray({-15, -13, -11}, {30, 30, 24}), Device::CPU);
    fillDense(dense, randomSdf);
    Scene<VoxelF, VoxelBlockHash> hash(testParams(), VoxelBlockHash(smallHash()), Device::CPU);
    fillHash(hash, {-15, -13, -11}, {15, 17, 13}, randomSdf);
    const Mesh dense_mesh = meshOf(dense), hash_mesh = meshOf(hash);
    ASSERT_GT(dense_mesh.triangles.size(), 20000u);
    expectWellFormed(dense_mesh, false);
    const Topology t = topologyOf(dense_mesh);
    EXPECT_TRUE(t.closedAndOriented()) << t.open_edges << " open, " << t.overused_edges << " overused, "
                                       << t.misoriented_edges;
    EXPECT_EQ(t.degenerate_triangles, 0);
    expectSameMesh(dense_mesh, hash_mesh, 0.f);
}

TEST(MeshingEngine, NoSurfaceBetweenObservedAndUnobservedSpace) {
    Scene<VoxelF, PlainVoxelArray> scene(testParams(), PlainVoxelArray({-30, -30, -30}, {60, 60, 60}), Device::CPU);
    // Observed inside the sphere only: negative everywhere it was seen, so no surface at all.
    fillDense(scene, [](Vec3i p) { return VoxelValue{-1.f, length(toFloat(p) * kVoxel) < kRadius}; });
    EXPECT_TRUE(meshOf(scene).triangles.empty());

    // The sphere observed only where x < 0.05 m: an open cap, with no vertex where a cell has an unobserved corner.
    const int cut_voxel = 5;
    fillDense(scene, [&](Vec3i p) { return VoxelValue{sphereSdf(p).sdf, p.x < cut_voxel}; });
    const Mesh mesh = meshOf(scene);
    expectWellFormed(mesh, false);
    ASSERT_GT(mesh.triangles.size(), 2000u);
    const Topology t = topologyOf(mesh);
    EXPECT_GT(t.open_edges, 0);
    EXPECT_EQ(t.overused_edges + t.misoriented_edges, 0);
    for (const Vec3f& v : mesh.vertices) ASSERT_LE(v.x, float(cut_voxel - 1) * kVoxel + 1e-6f);
}

TEST(MeshingEngine, ResultDoesNotDependOnTheThreadCount) {
    Scene<VoxelSRgbLabel, VoxelBlockHash> hash(testParams(), VoxelBlockHash(smallHash()), Device::CPU);
    fillHash(hash, {-30, -30, -30}, {30, 30, 30}, sphereWithClassGaps);
    setCpuThreadCount(1);
    const Mesh one = meshOf(hash);
    setCpuThreadCount(std::max(cpuThreadCount(), 3));
    const Mesh many = meshOf(hash);
    setCpuThreadCount(0);
    ASSERT_EQ(one.vertices.size(), many.vertices.size());
    ASSERT_EQ(one.triangles.size(), many.triangles.size());
    for (std::size_t i = 0; i < one.vertices.size(); ++i) {
        ASSERT_EQ(one.vertices[i], many.vertices[i]);
        ASSERT_EQ(one.colors[i], many.colors[i]);
        ASSERT_EQ(one.labels[i], many.labels[i]);
    }
    for (std::size_t i = 0; i < one.triangles.size(); ++i) ASSERT_EQ(one.triangles[i], many.triangles[i]);
}

// A table that holds a block twice (damaged: by a bad map file or a bug) is refused, not meshed twice
// over lists that end early.
TEST(MeshingEngine, ATableHoldingABlockTwiceIsRefused) {
    Scene<VoxelS, VoxelBlockHash> scene(testParams(), VoxelBlockHash(smallHash()), Device::CPU);
    fillHash(scene, Vec3i{-30, -30, -30}, Vec3i{30, 30, 30}, sphereSdf);
    Mesh mesh;
    makeMeshingEngine<VoxelS, VoxelBlockHash>(Device::CPU)->extractMesh(scene, mesh);
    ASSERT_GT(mesh.triangles.size(), 1000u);
    HashEntry* entries = scene.index().state().entries;
    int first = -1, second = -1;
    for (int i = 0; i < scene.index().entryCount() && second < 0; ++i)
        if (entries[i].ptr >= 0) (first < 0 ? first : second) = i;
    ASSERT_GE(second, 0);
    entries[second].pos = entries[first].pos;
    try {
        makeMeshingEngine<VoxelS, VoxelBlockHash>(Device::CPU)->extractMesh(scene, mesh);
        FAIL() << "meshed a table that holds a block twice";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("1 of its"), std::string::npos) << e.what();
    }
}

TEST(MeshingEngine, EmptySceneGivesAnEmptyMesh) {
    Scene<VoxelS, VoxelBlockHash> hash(testParams(), VoxelBlockHash(smallHash()), Device::CPU);
    Mesh mesh;
    mesh.vertices.push_back({1.f, 2.f, 3.f});  // replaced, not appended to
    mesh.triangles.push_back({0, 0, 0});
    makeMeshingEngine<VoxelS, VoxelBlockHash>(Device::CPU)->extractMesh(hash, mesh);
    EXPECT_TRUE(mesh.vertices.empty());
    EXPECT_TRUE(mesh.triangles.empty());
}

}  // namespace
}  // namespace voxfuse
