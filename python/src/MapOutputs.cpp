// voxfuse.Mesh and voxfuse.PointCloud: the library's outputs with their arrays viewed in place (an
// array keeps its mesh alive), writable to PLY/OBJ/STL by the library's writers.

#include "MapOutputs.h"

#include <pybind11/stl.h>

#include "Bindings.h"
#include "NumpyArrays.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/MeshLabels.h"
#include "voxfuse/engines/PointCloudDownsampling.h"
#include "voxfuse/io/MeshIO.h"

namespace voxfuse::python {

namespace {

template <class TOutput>
py::object colorsOf(const std::shared_ptr<TOutput>& o, bool has) {
    return has ? py::object(rowsOf<std::uint8_t, 3>(o, o->colors)) : py::none();
}
template <class TOutput>
py::object labelsOf(const std::shared_ptr<TOutput>& o, bool has) {
    return has ? py::object(rowsOf<ClassId, 1>(o, o->labels)) : py::none();
}
std::vector<ClassId> classList(const std::vector<int>& classes) {
    std::vector<ClassId> out;
    for (int c : classes) {
        if (c < 0 || c > 65535) throw ConfigError("class ids are 0..65535, not " + std::to_string(c));
        out.push_back(ClassId(c));
    }
    return out;
}

}  // namespace

void bindMapOutputs(py::module_& m) {
    py::class_<MeshOutput>(
        m, "Mesh",
        "A triangle mesh from marching cubes: no two vertices are equal, triangles are counter-clockwise\n"
        "seen from free space. Arrays view the mesh (no copy). Hand it to Open3D with\n"
        "o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(m.vertices), o3d.utility.Vector3iVector(m.faces)),\n"
        "or to trimesh with trimesh.Trimesh(m.vertices, m.faces, vertex_normals=m.normals).")
        .def_property_readonly(
            "vertices", [](const MeshOutput& o) { return rowsOf<float, 3>(o.mesh, o.mesh->vertices); },
            "float32 (N, 3), world coordinates in metres.")
        .def_property_readonly(
            "faces", [](const MeshOutput& o) { return rowsOf<std::int32_t, 3>(o.mesh, o.mesh->triangles); },
            "int32 (M, 3) vertex indices.")
        .def_property_readonly(
            "normals", [](const MeshOutput& o) { return rowsOf<float, 3>(o.mesh, o.mesh->normals); },
            "float32 (N, 3) unit normals pointing to free space.")
        .def_property_readonly(
            "colors", [](const MeshOutput& o) { return colorsOf(o.mesh, o.has_colors); },
            "uint8 (N, 3) RGB, or None for voxel types without colour.")
        .def_property_readonly(
            "labels", [](const MeshOutput& o) { return labelsOf(o.mesh, o.has_labels); },
            "uint16 (N,) semantic classes (65535: none), or None for voxel types without classes.")
        .def(
            "save",
            [](const MeshOutput& o, const std::string& path) {
                py::gil_scoped_release no_gil;
                writeMesh(path, *o.mesh);
            },
            py::arg("path"),
            "Writes .ply (binary, with normals, colours and classes), .obj or .stl; nothing half-written on failure.")
        .def(
            "select_classes",
            [](const MeshOutput& o, const std::vector<int>& classes, bool keep) {
                if (!o.has_labels)
                    throw ConfigError(
                        "select_classes needs a mesh of a voxel type with classes (s_label, s_rgb_label)");
                return MeshOutput{
                    std::make_shared<Mesh>(selectClasses(*o.mesh, classList(classes),
                                                         keep ? ClassSelection::Keep : ClassSelection::Exclude)),
                    o.has_colors, o.has_labels};
            },
            py::arg("classes"), py::arg("keep") = true,
            "The part of the mesh whose vertices have (keep) or have not these classes.")
        .def("__repr__", [](const MeshOutput& o) {
            return "<voxfuse.Mesh " + std::to_string(o.mesh->vertices.size()) + " vertices, " +
                   std::to_string(o.mesh->triangles.size()) + " triangles>";
        });

    py::class_<CloudOutput>(
        m, "PointCloud",
        "Surface points (one per zero crossing of a voxel edge) with normals, colours and classes.\n"
        "Hand it to Open3D with o3d.geometry.PointCloud(o3d.utility.Vector3dVector(c.points)).")
        .def_property_readonly(
            "points", [](const CloudOutput& o) { return rowsOf<float, 3>(o.cloud, o.cloud->points); },
            "float32 (N, 3), world coordinates in metres.")
        .def_property_readonly(
            "normals", [](const CloudOutput& o) { return rowsOf<float, 3>(o.cloud, o.cloud->normals); },
            "float32 (N, 3) unit normals pointing to free space.")
        .def_property_readonly(
            "colors", [](const CloudOutput& o) { return colorsOf(o.cloud, o.has_colors); },
            "uint8 (N, 3) RGB, or None for voxel types without colour.")
        .def_property_readonly(
            "labels", [](const CloudOutput& o) { return labelsOf(o.cloud, o.has_labels); },
            "uint16 (N,) semantic classes, or None for voxel types without classes.")
        .def("__len__", [](const CloudOutput& o) { return o.cloud->points.size(); })
        .def(
            "downsample",
            [](const CloudOutput& o, float cell_m) {
                if (!(cell_m > 0.f)) throw ConfigError("downsample: the cell size must be positive (metres)");
                py::gil_scoped_release no_gil;
                return CloudOutput{std::make_shared<PointCloud>(downsampleVoxelGrid(*o.cloud, cell_m)), o.has_colors,
                                   o.has_labels};
            },
            py::arg("cell_m"),
            "One point (the centroid, with averaged normal and colour) per occupied cell of cell_m metres.")
        .def(
            "save",
            [](const CloudOutput& o, const std::string& path) {
                py::gil_scoped_release no_gil;
                writePointCloudPly(path, *o.cloud);
            },
            py::arg("path"), "Writes a binary .ply with normals, colours and classes.")
        .def("__repr__", [](const CloudOutput& o) {
            return "<voxfuse.PointCloud " + std::to_string(o.cloud->points.size()) + " points>";
        });
}

}  // namespace voxfuse::python
