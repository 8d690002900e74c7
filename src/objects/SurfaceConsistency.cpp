// The consistency rules of Mesh and PointCloud, in one place for every writer and tool that takes them.

#include <cstddef>

#include "voxfuse/objects/Mesh.h"
#include "voxfuse/objects/PointCloud.h"

namespace voxfuse {
namespace {

// "" when every per-element attribute is empty or has `count` entries.
std::string attributeInconsistency(std::size_t count, const char* elements, std::size_t normals, std::size_t colors,
                                   std::size_t labels) {
    const std::pair<std::size_t, const char*> attributes[] = {
        {normals, "normals"}, {colors, "colours"}, {labels, "labels"}};
    for (const auto& [n, name] : attributes)
        if (n != 0 && n != count)
            return std::to_string(n) + " " + name + " for " + std::to_string(count) + " " + elements;
    return "";
}

}  // namespace

std::string inconsistency(const Mesh& mesh) {
    const std::size_t n = mesh.vertices.size();
    std::string why =
        attributeInconsistency(n, "vertices", mesh.normals.size(), mesh.colors.size(), mesh.labels.size());
    for (std::size_t t = 0; why.empty() && t < mesh.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k)
            if (mesh.triangles[t][k] < 0 || std::size_t(mesh.triangles[t][k]) >= n) {
                why = "triangle " + std::to_string(t) + " refers to vertex " + std::to_string(mesh.triangles[t][k]) +
                      " of " + std::to_string(n);
                break;
            }
    return why;
}

std::string inconsistency(const PointCloud& cloud) {
    return attributeInconsistency(cloud.points.size(), "points", cloud.normals.size(), cloud.colors.size(),
                                  cloud.labels.size());
}

}  // namespace voxfuse
