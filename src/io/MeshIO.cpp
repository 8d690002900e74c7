// Mesh and point-cloud writers: binary PLY, OBJ and binary STL.

#include "voxfuse/io/MeshIO.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "voxfuse/core/Error.h"
#include "voxfuse/io/AtomicFile.h"

namespace voxfuse {
namespace {

// Buffers bytes in little-endian order whatever the host's order, and writes them in large chunks to
// a file that appears under its name only once complete (io/AtomicFile.h).
class BinaryFile {
public:
    explicit BinaryFile(const std::string& path) : file_(path) { buffer_.reserve(kChunk + 64); }
    void text(const std::string& s) {
        buffer_.append(s);
        flushIfFull();
    }
    void u8(std::uint8_t v) { buffer_.push_back(char(v)); }
    void u16(std::uint16_t v) {
        u8(std::uint8_t(v));
        u8(std::uint8_t(v >> 8));
    }
    void u32(std::uint32_t v) {
        for (int shift = 0; shift < 32; shift += 8) u8(std::uint8_t(v >> shift));
        flushIfFull();
    }
    void i32(std::int32_t v) { u32(std::uint32_t(v)); }
    void f32(float v) {
        std::uint32_t bits;
        std::memcpy(&bits, &v, sizeof bits);
        u32(bits);
    }
    void vec3(Vec3f v) {
        f32(v.x);
        f32(v.y);
        f32(v.z);
    }
    void color(Vec3u8 c) {
        u8(c.x);
        u8(c.y);
        u8(c.z);
    }
    // Flushes and moves the file into place; throws when any write failed (e.g. a full disk).
    void finish() {
        flush();
        file_.commit();
    }

private:
    static constexpr std::size_t kChunk = std::size_t(1) << 20;
    void flushIfFull() {
        if (buffer_.size() >= kChunk) flush();
    }
    void flush() {
        file_.stream().write(buffer_.data(), std::streamsize(buffer_.size()));
        buffer_.clear();
        file_.check();
    }
    AtomicFile file_;
    std::string buffer_;
};

template <class TSurface>
void checkConsistent(const std::string& path, const TSurface& surface) {
    const std::string why = inconsistency(surface);
    if (!why.empty()) throw IoError(path, "inconsistent data: " + why);
}

// The label property has ScanNet's name and type (its *_vh_clean_2.labels.ply files), which their tools read.
std::string plyVertexHeader(std::size_t count, bool normals, bool colors, bool labels) {
    std::string h =
        "element vertex " + std::to_string(count) + "\nproperty float x\nproperty float y\nproperty float z\n";
    if (normals) h += "property float nx\nproperty float ny\nproperty float nz\n";
    if (colors) h += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    if (labels) h += "property ushort label\n";
    return h;
}

void writePlyVertices(BinaryFile& file, const std::vector<Vec3f>& points, const std::vector<Vec3f>& normals,
                      const std::vector<Vec3u8>& colors, const std::vector<ClassId>& labels) {
    for (std::size_t i = 0; i < points.size(); ++i) {
        file.vec3(points[i]);
        if (!normals.empty()) file.vec3(normals[i]);
        if (!colors.empty()) file.color(colors[i]);
        if (!labels.empty()) file.u16(labels[i]);
    }
}

// Shortest text that reads back to the same float.
void appendFloat(std::string& out, float v) {
    char buf[32];
    const auto result = std::to_chars(buf, buf + sizeof buf, v);
    out.append(buf, result.ptr);
}

void appendInt(std::string& out, long long v) {
    char buf[24];
    const auto result = std::to_chars(buf, buf + sizeof buf, v);
    out.append(buf, result.ptr);
}

std::string lowerExtension(const std::string& path) {
    const std::size_t slash = path.find_last_of("/\\");
    const std::size_t dot = path.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
    std::string ext = path.substr(dot);
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

}  // namespace

void writeMeshPly(const std::string& path, const Mesh& mesh) {
    checkConsistent(path, mesh);
    BinaryFile file(path);
    file.text("ply\nformat binary_little_endian 1.0\ncomment written by VoxFuse\n" +
              plyVertexHeader(mesh.vertices.size(), mesh.hasNormals(), mesh.hasColors(), mesh.hasLabels()) +
              "element face " + std::to_string(mesh.triangles.size()) +
              "\nproperty list uchar int vertex_indices\nend_header\n");
    writePlyVertices(file, mesh.vertices, mesh.normals, mesh.colors, mesh.labels);
    for (const Vec3i& t : mesh.triangles) {
        file.u8(3);
        for (int k = 0; k < 3; ++k) file.i32(t[k]);
    }
    file.finish();
}

void writePointCloudPly(const std::string& path, const PointCloud& cloud) {
    checkConsistent(path, cloud);
    BinaryFile file(path);
    file.text("ply\nformat binary_little_endian 1.0\ncomment written by VoxFuse\n" +
              plyVertexHeader(cloud.points.size(), cloud.hasNormals(), cloud.hasColors(), cloud.hasLabels()) +
              "end_header\n");
    writePlyVertices(file, cloud.points, cloud.normals, cloud.colors, cloud.labels);
    file.finish();
}

void writeMeshObj(const std::string& path, const Mesh& mesh) {
    checkConsistent(path, mesh);
    BinaryFile file(path);  // OBJ is text, but written verbatim ("\n" line ends on every platform)
    std::string line = "# written by VoxFuse: " + std::to_string(mesh.vertices.size()) + " vertices, " +
                       std::to_string(mesh.triangles.size()) + " triangles\n";
    file.text(line);
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        line = "v";
        for (int a = 0; a < 3; ++a) appendFloat(line += ' ', mesh.vertices[i][a]);
        if (mesh.hasColors())
            for (int a = 0; a < 3; ++a) appendFloat(line += ' ', float(mesh.colors[i][a]) / 255.f);
        line += '\n';
        file.text(line);
    }
    for (const Vec3f& n : mesh.normals) {
        line = "vn";
        for (int a = 0; a < 3; ++a) appendFloat(line += ' ', n[a]);
        line += '\n';
        file.text(line);
    }
    for (const Vec3i& t : mesh.triangles) {
        line = "f";
        for (int k = 0; k < 3; ++k) {
            appendInt(line += ' ', (long long)t[k] + 1);
            if (mesh.hasNormals()) appendInt(line += "//", (long long)t[k] + 1);
        }
        line += '\n';
        file.text(line);
    }
    file.finish();
}

void writeMeshStl(const std::string& path, const Mesh& mesh) {
    checkConsistent(path, mesh);
    if (mesh.triangles.size() > std::size_t(UINT32_MAX))
        throw IoError(path, "too many triangles for STL (at most 2^32 - 1)");
    BinaryFile file(path);
    std::string header = "binary STL written by VoxFuse";
    header.resize(80, ' ');  // must not start with "solid": readers would take it for ASCII STL
    file.text(header);
    file.u32(std::uint32_t(mesh.triangles.size()));
    for (const Vec3i& t : mesh.triangles) {
        const Vec3f a = mesh.vertices[std::size_t(t.x)], b = mesh.vertices[std::size_t(t.y)],
                    c = mesh.vertices[std::size_t(t.z)];
        file.vec3(normalize(cross(b - a, c - a)));
        file.vec3(a);
        file.vec3(b);
        file.vec3(c);
        file.u16(0);
    }
    file.finish();
}

void writeMesh(const std::string& path, const Mesh& mesh) {
    const std::string ext = lowerExtension(path);
    if (ext == ".ply") return writeMeshPly(path, mesh);
    if (ext == ".obj") return writeMeshObj(path, mesh);
    if (ext == ".stl") return writeMeshStl(path, mesh);
    throw IoError(path, "unknown mesh format '" + ext + "' (expected .ply, .obj or .stl)");
}

bool isMeshFileName(const std::string& path) {
    const std::string ext = lowerExtension(path);
    return ext == ".ply" || ext == ".obj" || ext == ".stl";
}

}  // namespace voxfuse
