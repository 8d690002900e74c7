#pragma once
// Selecting semantic classes on extracted surfaces: which classes a mesh or cloud has, the part of it
// that has (or has not) some classes, and one mesh per class for export.
//
// A mesh's classes are its triangles' classes. Marching cubes gives classes to vertices, so a triangle
// takes the class of two or three of its vertices when they agree, otherwise the class of its first
// vertex: every triangle belongs to exactly one class, and the per-class meshes of a mesh partition
// its triangles (each appears in exactly one). kNoLabel counts as a class of its own (the unlabelled
// part of the surface). A vertex on a border between classes is copied into each class that uses it.
//
// Every function throws Error when the mesh or cloud has no labels (voxel types without labels give
// none; an empty one is fine) or is inconsistent (attributes not one per vertex, a triangle index out
// of range). All run in time linear in the size of the mesh.

#include <cstddef>
#include <vector>

#include "voxfuse/objects/ClassLabel.h"
#include "voxfuse/objects/Mesh.h"
#include "voxfuse/objects/PointCloud.h"

namespace voxfuse {

enum class ClassSelection {
    Keep,    // the triangles or points whose class is in the list
    Exclude  // those whose class is not
};

// The class of triangle `triangle` (see above): its vertices' class when at least two agree, else
// its first vertex's.
ClassId triangleClass(const Mesh& mesh, std::size_t triangle);

// The classes of the mesh's triangles (of the cloud's points), ascending and each once; kNoLabel, the
// largest id, comes last where present.
std::vector<ClassId> classesOf(const Mesh& mesh);
std::vector<ClassId> classesOf(const PointCloud& cloud);

// The triangles whose class is (Keep) or is not (Exclude) in `classes`, with only the vertices they
// use: renumbered in their original order, with their normals, colours and labels.
Mesh selectClasses(const Mesh& mesh, const std::vector<ClassId>& classes, ClassSelection mode);
// The points whose label is (Keep) or is not (Exclude) in `classes`, in their original order.
PointCloud selectClasses(const PointCloud& cloud, const std::vector<ClassId>& classes, ClassSelection mode);

// One mesh per class of classesOf(mesh), in that order; part i equals
// selectClasses(mesh, {part i's class}, ClassSelection::Keep). Faster than selecting each class in turn
// when there are many classes.
struct ClassMesh {
    ClassId label;
    Mesh mesh;
};
std::vector<ClassMesh> splitByClass(const Mesh& mesh);

}  // namespace voxfuse
