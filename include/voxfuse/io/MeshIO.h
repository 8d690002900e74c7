#pragma once
// Writing meshes and point clouds. Every writer throws IoError naming the file when it cannot be
// written or when the mesh is inconsistent (normals, colours or labels not one per vertex, a triangle
// index out of range); nothing is written in the latter case. Only PLY stores semantic classes: OBJ
// and STL ignore mesh.labels (export one file per class with engines/MeshLabels.h instead).

#include <string>

#include "voxfuse/objects/Mesh.h"
#include "voxfuse/objects/PointCloud.h"

namespace voxfuse {

// Binary little-endian PLY: element vertex with float x y z, float nx ny nz (when the mesh has
// normals), uchar red green blue (when it has colours) and ushort label (when it has labels, as
// ScanNet's labelled meshes; kNoLabel is written as 65535); element face with "list uchar int
// vertex_indices".
void writeMeshPly(const std::string& path, const Mesh& mesh);
// Wavefront OBJ: "v x y z", followed by " r g b" in 0..1 when the mesh has colours (the vertex-colour
// extension MeshLab, CloudCompare and Open3D read); "vn" normals; faces "f a//a b//b c//c" (1-based),
// or "f a b c" without normals. No labels.
void writeMeshObj(const std::string& path, const Mesh& mesh);
// Binary STL: 80-byte header, triangle count, then per triangle its unit facet normal (from the
// vertices' winding; zero for a degenerate triangle), its three vertices and a zero attribute word.
// STL stores neither vertex normals nor colours nor labels.
void writeMeshStl(const std::string& path, const Mesh& mesh);
// Picks the format by extension: .ply, .obj or .stl (any case); IoError for anything else.
void writeMesh(const std::string& path, const Mesh& mesh);
// Whether writeMesh can write to `path` (its extension), for checking output names before a run.
bool isMeshFileName(const std::string& path);

// Binary little-endian PLY with element vertex only (x y z, nx ny nz, red green blue and label as above).
void writePointCloudPly(const std::string& path, const PointCloud& cloud);

}  // namespace voxfuse
