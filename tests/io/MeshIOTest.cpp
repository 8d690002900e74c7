// Mesh and point-cloud writers: PLY read back by a small parser, OBJ and STL contents checked line by
// line and byte by byte, and errors that name the file.

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "IoTestUtil.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/MeshIO.h"

namespace voxfuse {
namespace {

using test::readBytes;
using test::ScratchDir;

// A tetrahedron with exact binary fractions, so that text round trips are exact too.
Mesh tetrahedron(bool normals, bool colors) {
    Mesh m;
    m.vertices = {{0.f, 0.f, 0.f}, {1.f, 0.f, 0.f}, {0.f, 1.f, 0.f}, {0.f, 0.f, 1.5f}};
    if (normals) m.normals = {{-0.5f, -0.5f, -0.5f}, {1.f, 0.f, 0.f}, {0.f, 1.f, 0.f}, {0.f, 0.f, 1.f}};
    if (colors) m.colors = {{0, 0, 0}, {255, 0, 0}, {0, 128, 0}, {1, 2, 255}};
    m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    return m;
}

// ---- A minimal binary little-endian PLY reader ----

struct PlyContents {
    std::vector<std::string> header;  // lines up to and including end_header
    std::vector<Vec3f> points, normals;
    std::vector<Vec3u8> colors;
    std::vector<std::uint16_t> labels;
    std::vector<Vec3i> faces;
    std::size_t trailing_bytes = 0;
};

template <typename T>
T take(const std::string& bytes, std::size_t& at) {
    T v;
    std::memcpy(&v, bytes.data() + at, sizeof v);  // the test machine is little-endian, like the file
    at += sizeof v;
    return v;
}

PlyContents readPly(const std::string& path) {
    const std::string bytes = readBytes(path);
    PlyContents c;
    std::size_t at = 0;
    std::size_t vertex_count = 0, face_count = 0;
    bool has_normals = false, has_colors = false, has_labels = false;
    while (at < bytes.size()) {
        const std::size_t end = bytes.find('\n', at);
        EXPECT_NE(end, std::string::npos);
        if (end == std::string::npos) return c;
        const std::string line = bytes.substr(at, end - at);
        at = end + 1;
        c.header.push_back(line);
        std::istringstream words(line);
        std::string first, second;
        words >> first >> second;
        if (first == "element" && second == "vertex") words >> vertex_count;
        if (first == "element" && second == "face") words >> face_count;
        if (line == "property float nx") has_normals = true;
        if (line == "property uchar red") has_colors = true;
        if (line == "property ushort label") has_labels = true;
        if (line == "end_header") break;
    }
    const std::size_t vertex_bytes = 12 + (has_normals ? 12 : 0) + (has_colors ? 3 : 0) + (has_labels ? 2 : 0);
    EXPECT_GE(bytes.size(), at + vertex_count * vertex_bytes + face_count * 13);
    if (bytes.size() < at + vertex_count * vertex_bytes + face_count * 13) return c;
    for (std::size_t i = 0; i < vertex_count; ++i) {
        c.points.push_back({take<float>(bytes, at), take<float>(bytes, at), take<float>(bytes, at)});
        if (has_normals) c.normals.push_back({take<float>(bytes, at), take<float>(bytes, at), take<float>(bytes, at)});
        if (has_colors)
            c.colors.push_back(
                {take<std::uint8_t>(bytes, at), take<std::uint8_t>(bytes, at), take<std::uint8_t>(bytes, at)});
        if (has_labels) c.labels.push_back(take<std::uint16_t>(bytes, at));
    }
    for (std::size_t i = 0; i < face_count; ++i) {
        EXPECT_EQ(take<std::uint8_t>(bytes, at), 3);
        c.faces.push_back(
            {take<std::int32_t>(bytes, at), take<std::int32_t>(bytes, at), take<std::int32_t>(bytes, at)});
    }
    c.trailing_bytes = bytes.size() - at;
    return c;
}

TEST(MeshIO, PlyRoundTripWithNormalsAndColors) {
    ScratchDir dir;
    const Mesh m = tetrahedron(true, true);
    writeMeshPly(dir.file("mesh.ply"), m);
    const PlyContents c = readPly(dir.file("mesh.ply"));
    ASSERT_GE(c.header.size(), 3u);
    EXPECT_EQ(c.header[0], "ply");
    EXPECT_EQ(c.header[1], "format binary_little_endian 1.0");
    const std::vector<std::string> expected_properties = {
        "element vertex 4",    "property float x",   "property float y",
        "property float z",    "property float nx",  "property float ny",
        "property float nz",   "property uchar red", "property uchar green",
        "property uchar blue", "element face 4",     "property list uchar int vertex_indices",
        "end_header"};
    const std::vector<std::string> properties(c.header.end() - std::ptrdiff_t(expected_properties.size()),
                                              c.header.end());
    EXPECT_EQ(properties, expected_properties);
    EXPECT_EQ(c.points, m.vertices);
    EXPECT_EQ(c.normals, m.normals);
    EXPECT_EQ(c.colors, m.colors);
    EXPECT_EQ(c.faces, m.triangles);
    EXPECT_EQ(c.trailing_bytes, 0u);
}

TEST(MeshIO, PlyWithoutNormalsOrColorsDeclaresOnlyPositions) {
    ScratchDir dir;
    const Mesh m = tetrahedron(false, false);
    writeMesh(dir.file("plain.PLY"), m);  // chosen by extension, any case
    const PlyContents c = readPly(dir.file("plain.PLY"));
    for (const std::string& line : c.header) {
        EXPECT_EQ(line.find("nx"), std::string::npos);
        EXPECT_EQ(line.find("red"), std::string::npos);
    }
    EXPECT_EQ(c.points, m.vertices);
    EXPECT_TRUE(c.normals.empty());
    EXPECT_EQ(c.faces, m.triangles);
    EXPECT_EQ(c.trailing_bytes, 0u);
    // Header, then 4 x 12 vertex bytes, then 4 x 13 face bytes.
    const std::size_t header_bytes = readBytes(dir.file("plain.PLY")).find("end_header\n") + 11;
    EXPECT_EQ(std::filesystem::file_size(dir.file("plain.PLY")), header_bytes + 4 * 12 + 4 * 13);
}

TEST(MeshIO, PointCloudPlyHasVerticesOnly) {
    ScratchDir dir;
    PointCloud cloud;
    cloud.points = {{0.5f, -1.25f, 2.f}, {3.f, 4.f, 5.f}};
    cloud.normals = {{0.f, 0.f, 1.f}, {1.f, 0.f, 0.f}};
    cloud.colors = {{9, 8, 7}, {6, 5, 4}};
    writePointCloudPly(dir.file("cloud.ply"), cloud);
    const PlyContents c = readPly(dir.file("cloud.ply"));
    for (const std::string& line : c.header) EXPECT_EQ(line.find("element face"), std::string::npos);
    EXPECT_EQ(c.points, cloud.points);
    EXPECT_EQ(c.normals, cloud.normals);
    EXPECT_EQ(c.colors, cloud.colors);
    EXPECT_EQ(c.trailing_bytes, 0u);
}

// Classes as ScanNet's labelled meshes store them: "property ushort label" after the colours.
TEST(MeshIO, PlyWithLabelsHasAUshortLabelAfterTheColors) {
    ScratchDir dir;
    Mesh m = tetrahedron(true, true);
    m.labels = {3, 0, kNoLabel, 0x1234};  // 0x1234 tells the byte order
    writeMesh(dir.file("labelled.ply"), m);
    const PlyContents c = readPly(dir.file("labelled.ply"));
    const std::vector<std::string> expected_properties = {
        "property uchar red", "property uchar green", "property uchar blue", "property ushort label", "element face 4"};
    const std::vector<std::string> properties(c.header.end() - 2 - std::ptrdiff_t(expected_properties.size()),
                                              c.header.end() - 2);
    EXPECT_EQ(properties, expected_properties);
    EXPECT_EQ(c.points, m.vertices);
    EXPECT_EQ(c.normals, m.normals);
    EXPECT_EQ(c.colors, m.colors);
    EXPECT_EQ(c.labels, m.labels);
    EXPECT_EQ(c.faces, m.triangles);
    EXPECT_EQ(c.trailing_bytes, 0u);
    const std::string bytes = readBytes(dir.file("labelled.ply"));
    const std::size_t last_label =
        bytes.find("end_header\n") + 11 + 3 * 29 + 27;  // vertex 3's label: 27 bytes into its 29
    EXPECT_EQ(std::uint8_t(bytes[last_label]), 0x34) << "little-endian";
    EXPECT_EQ(std::uint8_t(bytes[last_label + 1]), 0x12);

    // A cloud without normals or colours: positions and labels only.
    PointCloud cloud;
    cloud.points = {{0.5f, -1.25f, 2.f}, {3.f, 4.f, 5.f}, {6.f, 7.f, 8.f}};
    cloud.labels = {7, kNoLabel, 40};
    writePointCloudPly(dir.file("labelled_cloud.ply"), cloud);
    const PlyContents cc = readPly(dir.file("labelled_cloud.ply"));
    const std::vector<std::string> expected_cloud = {"element vertex 3", "property float x",      "property float y",
                                                     "property float z", "property ushort label", "end_header"};
    const std::vector<std::string> cloud_properties(cc.header.end() - std::ptrdiff_t(expected_cloud.size()),
                                                    cc.header.end());
    EXPECT_EQ(cloud_properties, expected_cloud);
    EXPECT_EQ(cc.points, cloud.points);
    EXPECT_EQ(cc.labels, cloud.labels);
    EXPECT_EQ(cc.trailing_bytes, 0u);

    // Without labels, no label property.
    writeMeshPly(dir.file("unlabelled.ply"), tetrahedron(true, true));
    for (const std::string& line : readPly(dir.file("unlabelled.ply")).header)
        EXPECT_EQ(line.find("label"), std::string::npos);
}

TEST(MeshIO, ObjAndStlIgnoreLabelsAndBadLabelCountsAreRefused) {
    ScratchDir dir;
    Mesh labelled = tetrahedron(true, true);
    labelled.labels = {1, 2, 3, 4};
    writeMeshObj(dir.file("labelled.obj"), labelled);
    writeMeshObj(dir.file("plain.obj"), tetrahedron(true, true));
    EXPECT_EQ(readBytes(dir.file("labelled.obj")), readBytes(dir.file("plain.obj")));
    writeMeshStl(dir.file("labelled.stl"), labelled);
    writeMeshStl(dir.file("plain.stl"), tetrahedron(true, true));
    EXPECT_EQ(readBytes(dir.file("labelled.stl")), readBytes(dir.file("plain.stl")));

    labelled.labels.pop_back();
    EXPECT_THROW(writeMeshPly(dir.file("bad.ply"), labelled), IoError);
    EXPECT_FALSE(std::filesystem::exists(dir.file("bad.ply")));
    PointCloud cloud;
    cloud.points = {{0.f, 0.f, 0.f}};
    cloud.labels = {1, 2};
    EXPECT_THROW(writePointCloudPly(dir.file("bad_cloud.ply"), cloud), IoError);
}

std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) out.push_back(line);
    return out;
}

TEST(MeshIO, ObjHasColoredVerticesNormalsAndOneBasedFaces) {
    ScratchDir dir;
    writeMeshObj(dir.file("mesh.obj"), tetrahedron(true, true));
    const std::vector<std::string> l = lines(readBytes(dir.file("mesh.obj")));
    ASSERT_EQ(l.size(), 1u + 4 + 4 + 4);
    EXPECT_EQ(l[0][0], '#');
    EXPECT_EQ(l[1], "v 0 0 0 0 0 0");
    EXPECT_EQ(l[2], "v 1 0 0 1 0 0");
    // 128 / 255 written as the shortest float text that reads back to the same float.
    EXPECT_EQ(l[3].substr(0, 10), "v 0 1 0 0 ");
    EXPECT_EQ(std::stof(l[3].substr(10)), 128.f / 255.f);
    EXPECT_EQ(l[4].substr(0, 8), "v 0 0 1.");
    EXPECT_EQ(l[5], "vn -0.5 -0.5 -0.5");
    EXPECT_EQ(l[8], "vn 0 0 1");
    EXPECT_EQ(l[9], "f 1//1 3//3 2//2");
    EXPECT_EQ(l[12], "f 2//2 3//3 4//4");
}

TEST(MeshIO, ObjWithoutNormalsOrColors) {
    ScratchDir dir;
    writeMesh(dir.file("mesh.obj"), tetrahedron(false, false));
    const std::vector<std::string> l = lines(readBytes(dir.file("mesh.obj")));
    ASSERT_EQ(l.size(), 1u + 4 + 4);
    EXPECT_EQ(l[4], "v 0 0 1.5");
    EXPECT_EQ(l[5], "f 1 3 2");
}

TEST(MeshIO, StlIsBinaryWithFacetNormals) {
    ScratchDir dir;
    const Mesh m = tetrahedron(true, true);
    writeMesh(dir.file("mesh.stl"), m);
    const std::string bytes = readBytes(dir.file("mesh.stl"));
    ASSERT_EQ(bytes.size(), 84u + 50u * m.triangles.size());
    EXPECT_NE(bytes.substr(0, 5), "solid") << "a binary STL must not look like an ASCII one";
    std::size_t at = 80;
    EXPECT_EQ(take<std::uint32_t>(bytes, at), 4u);
    // Triangle 0 = (0, 2, 1) lies in z = 0 and winds clockwise seen from +z: its normal is -z.
    EXPECT_EQ((Vec3f{take<float>(bytes, at), take<float>(bytes, at), take<float>(bytes, at)}), (Vec3f{0.f, 0.f, -1.f}));
    EXPECT_EQ((Vec3f{take<float>(bytes, at), take<float>(bytes, at), take<float>(bytes, at)}), m.vertices[0]);
    EXPECT_EQ((Vec3f{take<float>(bytes, at), take<float>(bytes, at), take<float>(bytes, at)}), m.vertices[2]);
    EXPECT_EQ((Vec3f{take<float>(bytes, at), take<float>(bytes, at), take<float>(bytes, at)}), m.vertices[1]);
    EXPECT_EQ(take<std::uint16_t>(bytes, at), 0u);
    // Triangle 1 = (0, 1, 3) lies in y = 0 with normal -y.
    EXPECT_EQ((Vec3f{take<float>(bytes, at), take<float>(bytes, at), take<float>(bytes, at)}), (Vec3f{0.f, -1.f, 0.f}));
}

TEST(MeshIO, ErrorsNameTheFile) {
    ScratchDir dir;
    const std::string missing_dir = dir.file("no/such") + "/dir/mesh.ply";
    std::filesystem::remove_all(dir.file("no/such"));
    try {
        writeMeshPly(missing_dir, tetrahedron(true, false));
        FAIL() << "expected IoError";
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), missing_dir);
        EXPECT_NE(std::string(e.what()).find(missing_dir), std::string::npos);
    }
    try {
        writeMesh(dir.file("mesh.xyz"), tetrahedron(false, false));
        FAIL() << "expected IoError";
    } catch (const IoError& e) {
        EXPECT_NE(e.reason().find(".xyz"), std::string::npos);
    }

    Mesh bad = tetrahedron(true, true);
    bad.triangles.push_back({0, 1, 4});
    const std::string path = dir.file("bad.obj");
    EXPECT_THROW(writeMeshObj(path, bad), IoError);
    EXPECT_FALSE(std::filesystem::exists(path)) << "nothing is written for an inconsistent mesh";
    bad = tetrahedron(true, true);
    bad.colors.pop_back();
    EXPECT_THROW(writeMeshStl(dir.file("bad.stl"), bad), IoError);
    PointCloud cloud;
    cloud.points = {{0.f, 0.f, 0.f}};
    cloud.normals = {{0.f, 0.f, 1.f}, {0.f, 0.f, 1.f}};
    EXPECT_THROW(writePointCloudPly(dir.file("bad_cloud.ply"), cloud), IoError);
}

TEST(MeshIO, EmptyMeshIsAValidFile) {
    ScratchDir dir;
    writeMeshPly(dir.file("empty.ply"), Mesh());
    const PlyContents c = readPly(dir.file("empty.ply"));
    EXPECT_EQ(c.header.back(), "end_header");
    EXPECT_TRUE(c.points.empty());
    EXPECT_EQ(c.trailing_bytes, 0u);
    writeMeshStl(dir.file("empty.stl"), Mesh());
    EXPECT_EQ(std::filesystem::file_size(dir.file("empty.stl")), 84u);
}

}  // namespace
}  // namespace voxfuse
