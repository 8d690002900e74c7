#pragma once
// A mesh or cloud handed to Python, with what its voxel type has (an empty mesh of a colour voxel
// type still has an (0, 3) colour array; a type without colour has None).

#include <memory>

#include "voxfuse/objects/Mesh.h"
#include "voxfuse/objects/PointCloud.h"

namespace voxfuse::python {

struct MeshOutput {
    std::shared_ptr<Mesh> mesh;
    bool has_colors = false, has_labels = false;
};

struct CloudOutput {
    std::shared_ptr<PointCloud> cloud;
    bool has_colors = false, has_labels = false;
};

}  // namespace voxfuse::python
