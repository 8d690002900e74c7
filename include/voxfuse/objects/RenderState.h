#pragma once
// The results of raycasting the model from one viewpoint: surface points and normals per pixel (used
// by the tracker at the next frame) and the rendered image.

#include "voxfuse/core/Image.h"
#include "voxfuse/objects/Intrinsics.h"

namespace voxfuse {

struct RenderState {
    Intrinsics intrinsics;                     // camera the rays were cast through
    Mat4f T_world_camera = Mat4f::identity();  // viewpoint of the raycast
    Image<Vec4f> points_world;                 // surface point per pixel, w = 1 where a surface was hit, 0 otherwise
    Image<Vec4f> normals_world;                // unit normal per pixel (w = 1 when valid)
    Image<Vec2f> depth_range;                  // per-pixel [min, max] search range along z, metres
    Image<float> intensity;  // the map's colour per pixel as an intensity in [0, 1], -1 where none; made only
                             // for the rgbd tracker's model (its colour term's reference), else empty

    // Sizes the images for `intr` on `where` (the raycast engine's device). On the GPU, points and
    // normals get pinned host memory for the copies the CPU-side tracker reads every frame.
    void resize(const Intrinsics& intr, Device where = Device::CPU) {
        intrinsics = intr;
        const bool host = where == Device::CPU, device = where == Device::CUDA;
        const HostMemory kind = device ? HostMemory::Pinned : HostMemory::Pageable;
        points_world.resize(intr.size(), host, device, kind);
        normals_world.resize(intr.size(), host, device, kind);
        depth_range.resize(intr.size(), host, device);
    }
    // Brings the host copies of points and normals up to date (after a raycast on the GPU).
    void updateHost() {
        points_world.memory().updateHost();
        normals_world.memory().updateHost();
    }
};

}  // namespace voxfuse
