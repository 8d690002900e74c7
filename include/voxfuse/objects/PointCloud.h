#pragma once
// Points on the reconstructed surface in world coordinates (metres), with normals and, when the voxel
// type has colour, colours. Written by io/MeshIO.h, thinned by engines/PointCloudDownsampling.h.

#include <cstddef>
#include <string>
#include <vector>

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/ClassLabel.h"

namespace voxfuse {

struct PointCloud {
    std::vector<Vec3f> points;   // world coordinates (m)
    std::vector<Vec3f> normals;  // one unit normal per point pointing to free space, or empty
    std::vector<Vec3u8> colors;  // one RGB colour per point, or empty
    std::vector<ClassId>
        labels;  // one semantic class per point (kNoLabel: none), or empty (voxel types without labels)

    std::size_t size() const { return points.size(); }
    bool empty() const { return points.empty(); }
    bool hasNormals() const { return !normals.empty(); }
    bool hasColors() const { return !colors.empty(); }
    bool hasLabels() const { return !labels.empty(); }
    void clear() {
        points.clear();
        normals.clear();
        colors.clear();
        labels.clear();
    }
};

// What is wrong with the cloud ("3 normals for 4 points"), or "" when its normals, colours and labels
// are each empty or one per point.
std::string inconsistency(const PointCloud& cloud);

}  // namespace voxfuse
