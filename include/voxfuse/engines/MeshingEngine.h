#pragma once
// Surface extraction from the scene: a triangle mesh by marching cubes, or the mesh's vertices alone
// as a point cloud. Its stages (src/engines/MeshingEngine_Impl.h) run on either device: per block,
// count the surface, scan, emit it (shared/Meshing.h, with the cells of shared/MarchingCubes.h).
//
// What the output is:
// - One vertex per voxel edge whose two ends were observed with opposite SDF signs, at the linear
//   zero crossing, and only where at least one of the four cells around the edge has all eight corners
//   observed (weight > 0). Only such complete cells produce triangles, so there is no surface between
//   observed and never-observed space. A vertex is shared by every triangle that uses it, across
//   voxel block borders too: no two vertices have the same position.
// - Normals: the SDF gradient (central differences of the voxels, one-sided beside unobserved ones) at
//   the edge's two ends, interpolated to the vertex and normalised; they point to free space.
// - Colours (voxel types with colour): the two ends' colours interpolated the same way.
// - Classes (voxel types with labels; mesh.labels / cloud.labels, empty otherwise): classes are not
//   interpolated. A vertex takes the class of the edge end nearer to it (the start where the crossing
//   is below the edge's middle) if that voxel has one (w_label > 0), else the other end's, else
//   kNoLabel.
// - Triangles wind counter-clockwise seen from free space. Their order, and the vertices', depends on
//   the scene only, not on the number of threads or the device.
// Memory: the mesh, plus about 130 bytes per block and 640 per block with surface. On the GPU the
// mesh is assembled there and only the finished arrays come down.

#include <memory>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/objects/Mesh.h"
#include "voxfuse/objects/PointCloud.h"
#include "voxfuse/objects/Scene.h"

namespace voxfuse {

template <class TVoxel, class TIndex>
class MeshingEngine {
public:
    virtual ~MeshingEngine() = default;
    // Replaces `mesh` (host memory) with the scene's surface. The scene must live on the engine's device.
    virtual void extractMesh(const Scene<TVoxel, TIndex>& scene, Mesh& mesh) = 0;
    // Replaces `cloud` with the vertices of extractMesh() (points, normals, colours, classes) without
    // building the triangles: one point per zero-crossing voxel edge.
    virtual void extractPointCloud(const Scene<TVoxel, TIndex>& scene, PointCloud& cloud) = 0;
};

namespace cpu {
template <class TVoxel, class TIndex>
std::unique_ptr<MeshingEngine<TVoxel, TIndex>> makeMeshingEngine();
}
namespace cuda {
template <class TVoxel, class TIndex>
std::unique_ptr<MeshingEngine<TVoxel, TIndex>> makeMeshingEngine();
}

// The engine of `device` for scenes on that device; DeviceError in a build without CUDA.
template <class TVoxel, class TIndex>
std::unique_ptr<MeshingEngine<TVoxel, TIndex>> makeMeshingEngine(Device device) {
    return device == Device::CPU ? cpu::makeMeshingEngine<TVoxel, TIndex>() : cuda::makeMeshingEngine<TVoxel, TIndex>();
}

}  // namespace voxfuse
