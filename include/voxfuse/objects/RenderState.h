#pragma once
// The results of raycasting the model from one viewpoint: surface points and normals per pixel (used
// by the tracker at the next frame) and the rendered image.

#include "voxfuse/core/Image.h"
#include "voxfuse/objects/Intrinsics.h"

namespace voxfuse {

struct RenderState {
    Intrinsics intrinsics;                    // camera the rays were cast through
    Mat4f T_world_camera = Mat4f::identity(); // viewpoint of the raycast
    Image<Vec4f> points_world;   // surface point per pixel, w = 1 where a surface was hit, 0 otherwise
    Image<Vec4f> normals_world;  // unit normal per pixel (w = 1 when valid)
    Image<Vec2f> depth_range;    // per-pixel [min, max] search range along z, metres

    void resize(const Intrinsics& intr) {
        intrinsics = intr;
        points_world.resize(intr.size());
        normals_world.resize(intr.size());
        depth_range.resize(intr.size());
    }
};

}  // namespace voxfuse
