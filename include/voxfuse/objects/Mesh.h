#pragma once
// An indexed triangle mesh in world coordinates (metres), as the meshing engine extracts it and the
// mesh writers (io/MeshIO.h) save it.

#include <cstddef>
#include <string>
#include <vector>

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/ClassLabel.h"

namespace voxfuse {

struct Mesh {
    std::vector<Vec3f> vertices;  // world coordinates (m); no two are equal
    std::vector<Vec3f> normals;   // one unit normal per vertex pointing to free space, or empty
    std::vector<Vec3u8> colors;   // one RGB colour per vertex, or empty (voxel types without colour)
    std::vector<ClassId>
        labels;  // one semantic class per vertex (kNoLabel: none), or empty (voxel types without labels)
    std::vector<Vec3i> triangles;  // vertex indices, counter-clockwise seen from free space

    bool hasNormals() const { return !normals.empty(); }
    bool hasColors() const { return !colors.empty(); }
    bool hasLabels() const { return !labels.empty(); }
    void clear() {
        vertices.clear();
        normals.clear();
        colors.clear();
        labels.clear();
        triangles.clear();
    }
    // Bytes held by the arrays (their sizes, not their capacities).
    std::size_t bytes() const {
        return vertices.size() * sizeof(Vec3f) + normals.size() * sizeof(Vec3f) + colors.size() * sizeof(Vec3u8) +
               labels.size() * sizeof(ClassId) + triangles.size() * sizeof(Vec3i);
    }
};

// What is wrong with the mesh ("3 normals for 4 vertices", "triangle 7 refers to vertex 9 of 4"), or
// "" when its normals, colours and labels are each empty or one per vertex and every triangle index
// is a vertex. Writers and the class tools check this before they use a mesh.
std::string inconsistency(const Mesh& mesh);

}  // namespace voxfuse
