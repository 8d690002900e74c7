// Class selection on meshes and point clouds: a class table for membership, a used-vertex pass for
// compaction, and for splitting the triangle corners listed by vertex.

#include "voxfuse/engines/MeshLabels.h"

#include <cstdint>
#include <string>

#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace {

constexpr std::size_t kClassCount = std::size_t(1) << (8 * sizeof(ClassId));  // every ClassId, kNoLabel included

// Class tools need labels (voxel types without them give none) and a consistent surface.
template <class TSurface>
void checkLabelled(const char* what, const TSurface& surface, std::size_t elements, const char* element) {
    if (surface.labels.empty() && elements > 0)
        throw Error(std::string(what) + ": the " + element +
                    " has no labels (only the voxel types with labels, s_label and s_rgb_label, give them)");
    const std::string why = inconsistency(surface);
    if (!why.empty()) throw Error(std::string(what) + ": inconsistent data: " + why);
}

void checkMesh(const char* what, const Mesh& mesh) { checkLabelled(what, mesh, mesh.vertices.size(), "mesh"); }
void checkCloud(const char* what, const PointCloud& cloud) {
    checkLabelled(what, cloud, cloud.points.size(), "point cloud");
}

// The rule of triangleClass() on a checked mesh.
ClassId classOfTriangle(const Mesh& mesh, const Vec3i& t) {
    const ClassId a = mesh.labels[std::size_t(t.x)], b = mesh.labels[std::size_t(t.y)],
                  c = mesh.labels[std::size_t(t.z)];
    return b == c ? b : a;  // b == c: two or three agree on b; otherwise a agrees with one of them, or none agree
}

// Whether each ClassId is selected: in `classes` for Keep, not in it for Exclude.
std::vector<bool> selectionTable(const std::vector<ClassId>& classes, ClassSelection mode) {
    std::vector<bool> selected(kClassCount, mode == ClassSelection::Exclude);
    for (const ClassId c : classes) selected[c] = mode == ClassSelection::Keep;
    return selected;
}

// The ids marked present, ascending.
std::vector<ClassId> presentIds(const std::vector<bool>& present) {
    std::vector<ClassId> classes;
    for (std::size_t c = 0; c < kClassCount; ++c)
        if (present[c]) classes.push_back(ClassId(c));
    return classes;
}

// The classes of a checked mesh's triangles, ascending.
std::vector<ClassId> presentClasses(const Mesh& mesh) {
    std::vector<bool> present(kClassCount, false);
    for (const Vec3i& t : mesh.triangles) present[classOfTriangle(mesh, t)] = true;
    return presentIds(present);
}

void appendVertex(const Mesh& from, std::size_t v, Mesh& to) {
    to.vertices.push_back(from.vertices[v]);
    if (from.hasNormals()) to.normals.push_back(from.normals[v]);
    if (from.hasColors()) to.colors.push_back(from.colors[v]);
    to.labels.push_back(from.labels[v]);
}

}  // namespace

ClassId triangleClass(const Mesh& mesh, std::size_t triangle) {
    if (triangle >= mesh.triangles.size())
        throw Error("triangleClass: triangle " + std::to_string(triangle) + " of " +
                    std::to_string(mesh.triangles.size()));
    if (mesh.labels.size() != mesh.vertices.size()) checkMesh("triangleClass", mesh);  // says what is wrong
    const Vec3i& t = mesh.triangles[triangle];
    for (int k = 0; k < 3; ++k)
        if (t[k] < 0 || std::size_t(t[k]) >= mesh.vertices.size())
            throw Error("triangleClass: inconsistent data: triangle " + std::to_string(triangle) +
                        " refers to vertex " + std::to_string(t[k]) + " of " + std::to_string(mesh.vertices.size()));
    return classOfTriangle(mesh, t);
}

std::vector<ClassId> classesOf(const Mesh& mesh) {
    checkMesh("classesOf", mesh);
    return presentClasses(mesh);
}

std::vector<ClassId> classesOf(const PointCloud& cloud) {
    checkCloud("classesOf", cloud);
    std::vector<bool> present(kClassCount, false);
    for (const ClassId c : cloud.labels) present[c] = true;
    return presentIds(present);
}

Mesh selectClasses(const Mesh& mesh, const std::vector<ClassId>& classes, ClassSelection mode) {
    checkMesh("selectClasses", mesh);
    const std::vector<bool> selected = selectionTable(classes, mode);
    constexpr int kUnused = -1, kUsed = -2;
    std::vector<int> new_index(mesh.vertices.size(), kUnused);
    std::vector<std::size_t> kept;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        if (!selected[classOfTriangle(mesh, mesh.triangles[t])]) continue;
        kept.push_back(t);
        for (int k = 0; k < 3; ++k) new_index[std::size_t(mesh.triangles[t][k])] = kUsed;
    }
    Mesh out;
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
        if (new_index[v] != kUsed) continue;
        new_index[v] = int(out.vertices.size());
        appendVertex(mesh, v, out);
    }
    out.triangles.reserve(kept.size());
    for (const std::size_t t : kept) {
        const Vec3i& tri = mesh.triangles[t];
        out.triangles.push_back(
            {new_index[std::size_t(tri.x)], new_index[std::size_t(tri.y)], new_index[std::size_t(tri.z)]});
    }
    return out;
}

PointCloud selectClasses(const PointCloud& cloud, const std::vector<ClassId>& classes, ClassSelection mode) {
    checkCloud("selectClasses", cloud);
    const std::vector<bool> selected = selectionTable(classes, mode);
    PointCloud out;
    for (std::size_t i = 0; i < cloud.points.size(); ++i) {
        if (!selected[cloud.labels[i]]) continue;
        out.points.push_back(cloud.points[i]);
        if (cloud.hasNormals()) out.normals.push_back(cloud.normals[i]);
        if (cloud.hasColors()) out.colors.push_back(cloud.colors[i]);
        out.labels.push_back(cloud.labels[i]);
    }
    return out;
}

std::vector<ClassMesh> splitByClass(const Mesh& mesh) {
    checkMesh("splitByClass", mesh);
    // Each triangle's part: the rank of its class among the classes present.
    std::vector<ClassMesh> parts;
    std::vector<int> part_of_class(kClassCount, -1);
    for (const ClassId c : presentClasses(mesh)) {
        part_of_class[c] = int(parts.size());
        parts.push_back({c, Mesh()});
    }
    std::vector<int> part_of_triangle(mesh.triangles.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        part_of_triangle[t] = part_of_class[classOfTriangle(mesh, mesh.triangles[t])];

    // The triangle corners of each vertex (a counting sort by vertex), so that the vertices can be
    // visited once in ascending order and each copied into every part that uses it.
    const std::size_t corner_count = 3 * mesh.triangles.size();
    std::vector<std::size_t> first_corner(mesh.vertices.size() + 1, 0);
    for (const Vec3i& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) ++first_corner[std::size_t(t[k]) + 1];
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v) first_corner[v + 1] += first_corner[v];
    std::vector<std::size_t> corners_by_vertex(corner_count), next = first_corner;
    for (std::size_t c = 0; c < corner_count; ++c)
        corners_by_vertex[next[std::size_t(mesh.triangles[c / 3][int(c % 3)])]++] = c;

    // Each corner's vertex index in its triangle's part.
    std::vector<int> corner_index(corner_count);
    std::vector<std::size_t> last_vertex_of_part(parts.size(), SIZE_MAX);
    std::vector<int> index_in_part(parts.size());
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v)
        for (std::size_t k = first_corner[v]; k < first_corner[v + 1]; ++k) {
            const std::size_t c = corners_by_vertex[k], p = std::size_t(part_of_triangle[c / 3]);
            if (last_vertex_of_part[p] != v) {
                last_vertex_of_part[p] = v;
                index_in_part[p] = int(parts[p].mesh.vertices.size());
                appendVertex(mesh, v, parts[p].mesh);
            }
            corner_index[c] = index_in_part[p];
        }
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        parts[std::size_t(part_of_triangle[t])].mesh.triangles.push_back(
            {corner_index[3 * t], corner_index[3 * t + 1], corner_index[3 * t + 2]});
    return parts;
}

}  // namespace voxfuse
