#pragma once
// Thinning a point cloud on a voxel grid by centroid (Algorithm 7 of the KinectFusion/OctoMap thesis
// cited in docs/DESIGN_NOTES.md): points are binned into cubic cells of side cell_m aligned with the
// world origin, and each occupied cell gives one point, the centroid of its points. Normals are averaged and
// renormalised (a cell whose normals cancel out gets a zero normal); colours are averaged and rounded.
// A cell's class is the most frequent class of its points, not counting kNoLabel unless no point has
// a class; of equally frequent classes the smallest id wins.

#include "voxfuse/objects/PointCloud.h"

namespace voxfuse {

// The output is ordered by cell (z, then y, then x). Points with a non-finite coordinate are dropped.
// Throws ConfigError when cell_m is not a positive number or is too small for the cloud's extent
// (cell indices must fit in 32 bits), and Error when the normals, colours or labels do not match the
// points.
PointCloud downsampleVoxelGrid(const PointCloud& cloud, float cell_m);

}  // namespace voxfuse
