#pragma once
// Casting one ray through the TSDF (section 4.4 of the InfiniTAM report): steps as long as the SDF
// allows (never shorter than a voxel), a trilinear refinement at the zero crossing, and no surface
// reported where a ray enters the band from behind (the report's WRONG_SIDE case).

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/Intrinsics.h"
#include "voxfuse/shared/VoxelAccess.h"

namespace voxfuse {

// Clips the ray origin + t * dir to an axis-aligned box [lo, hi]; false when it misses.
VF_HOST_DEVICE inline bool clipRayToBox(Vec3f origin, Vec3f dir, Vec3f lo, Vec3f hi, float& t_min, float& t_max) {
    for (int a = 0; a < 3; ++a) {
        if (fabsf(dir[a]) < 1e-12f) {
            if (origin[a] < lo[a] || origin[a] > hi[a]) return false;
            continue;
        }
        float t0 = (lo[a] - origin[a]) / dir[a], t1 = (hi[a] - origin[a]) / dir[a];
        if (t0 > t1) { const float s = t0; t0 = t1; t1 = s; }
        t_min = t0 > t_min ? t0 : t_min;
        t_max = t1 < t_max ? t1 : t_max;
    }
    return t_min <= t_max;
}

// Marches from origin + t_min * dir to origin + t_max * dir, all in grid units (dir unit length).
// `step_scale` is mu in voxels: an SDF value s (normalised to [-1, 1]) lets us step s * step_scale.
// On success writes the surface point (grid units) and returns true.
template <class TVoxel, class TIndexData>
VF_HOST_DEVICE inline bool castRay(Vec3f& hit_grid, const TVoxel* voxels, const TIndexData& index, Vec3f origin, Vec3f dir,
                                   float t_min, float t_max, float step_scale) {
    float t = t_min;
    float sdf = 1.f;
    bool seen_front = false;  // a positive (free-space) observation on this ray
    bool crossed = false;
    while (t < t_max) {
        bool observed;
        const Vec3f p = origin + dir * t;
        sdf = readSdfNearest(voxels, index, p, observed);
        if (!observed) {
            t += step_scale;  // nothing known here: a truncation band at a time
            continue;
        }
        if (sdf <= 0.1f && sdf >= -0.5f) sdf = readSdfInterpolated(voxels, index, p, observed);
        if (sdf <= 0.f) {
            if (seen_front) {
                crossed = true;
                break;
            }
            // Inside or behind a surface without having seen its front: move on until free space.
            t += step_scale * (-sdf > 0.25f ? -sdf : 0.25f);
            continue;
        }
        seen_front = true;
        t += sdf * step_scale > 1.f ? sdf * step_scale : 1.f;
    }
    if (!crossed) return false;

    // Two SDF-sized corrections around the crossing (sdf <= 0 here, so the first step goes back).
    bool observed;
    t += sdf * step_scale;
    sdf = readSdfInterpolated(voxels, index, origin + dir * t, observed);
    t += sdf * step_scale;
    hit_grid = origin + dir * t;
    return true;
}

// The unit-length ray direction through pixel (x, y) in camera coordinates and the factor that
// turns a depth z into a distance along that ray.
VF_HOST_DEVICE inline Vec3f pixelRayDirection(const Intrinsics& intr, float x, float y, float& distance_per_depth) {
    const Vec3f d{(x - intr.cx) / intr.fx, (y - intr.cy) / intr.fy, 1.f};
    distance_per_depth = length(d);
    return d / distance_per_depth;
}

// Lambertian shading with the light at the camera, as in InfiniTAM's renders (0.2 ambient floor).
VF_HOST_DEVICE inline unsigned char shadeIntensity(Vec3f normal, Vec3f to_camera_unit) {
    const float lambert = dot(normal, to_camera_unit);
    const float i = 0.2f + 0.8f * (lambert > 0.f ? lambert : 0.f);
    return (unsigned char)(255.f * i);
}

}  // namespace voxfuse
