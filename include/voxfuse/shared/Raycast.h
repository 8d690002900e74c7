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
            // Nothing known here: a truncation band at a time. The front seen before the gap still counts,
            // as inside an allocated hash block (castRayHash), so that both indexes find the same surfaces;
            // a back face met after a long unobserved gap is the price (dense cannot tell "never
            // allocated" from "not yet observed").
            t += step_scale;
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

// ---- The voxel block hash: the report's state machine ----

enum class RayState {
    SearchBlockCoarse,  // in unallocated space: jump to where the ray leaves the current block
    SearchBlockFine,    // just entered an allocated block: no positive (free-space) SDF seen yet
    SearchSurface,      // in front of a surface: SDF-sized steps until the SDF turns negative
    BehindSurface,      // crossed a surface from the front: done
    WrongSide           // entered an allocated block behind a surface: no surface until free space again
};

// Parameter t (along origin + t * dir, grid units) where the nearest-voxel rounding of the ray leaves
// block `block`, i.e. the box [8 * block - 0.5, 8 * block + 7.5] on every axis.
VF_HOST_DEVICE inline float rayBlockExit(Vec3f origin, Vec3f dir, Vec3i block) {
    float t_exit = 1e30f;
    for (int a = 0; a < 3; ++a) {
        if (fabsf(dir[a]) < 1e-12f) continue;
        const float face = dir[a] > 0.f ? float(block[a] * kBlockSide) + float(kBlockSide) - 0.5f : float(block[a] * kBlockSide) - 0.5f;
        const float t = (face - origin[a]) / dir[a];
        t_exit = t < t_exit ? t : t_exit;
    }
    return t_exit;
}

// castRay() for the voxel block hash (TIndexData: VoxelBlockHash::Data or CachedHashView): the same
// steps, thresholds and refinement inside allocated blocks, but unallocated blocks are crossed in one
// go, and a surface counts only when the ray saw its positive side after the last unallocated gap (the
// report's WRONG_SIDE: the boundary between unallocated space and negative values is no surface).
// Coarse steps are whole multiples of step_scale, the step castRay() takes through unobserved space,
// and the march starts on the lattice t_anchor + k * step_scale: where the search range starts and how
// the blocks are laid out never moves the samples, so the surface found depends on the SDF alone.
template <class TVoxel, class TIndexData>
VF_HOST_DEVICE inline bool castRayHash(Vec3f& hit_grid, const TVoxel* voxels, const TIndexData& index, Vec3f origin, Vec3f dir,
                                       float t_anchor, float t_min, float t_max, float step_scale) {
    RayState state = RayState::SearchBlockCoarse;
    float t = t_anchor + ceilf((t_min - t_anchor) / step_scale) * step_scale;
    float sdf = 1.f;
    while (t < t_max) {
        const Vec3f p = origin + dir * t;
        const Vec3i voxel{int(floorf(p.x + 0.5f)), int(floorf(p.y + 0.5f)), int(floorf(p.z + 0.5f))};
        bool allocated;
        const TVoxel v = readVoxel(voxels, index, voxel, allocated);
        if (!allocated) {
            state = RayState::SearchBlockCoarse;
            const float steps = ceilf((rayBlockExit(origin, dir, blockOfVoxel(voxel)) - t) / step_scale);
            t += (steps > 1.f ? steps : 1.f) * step_scale;
            continue;
        }
        if (state == RayState::SearchBlockCoarse) state = RayState::SearchBlockFine;
        if (v.w_depth == 0) {
            t += step_scale;  // unobserved voxels of an allocated block: a truncation band at a time
            continue;
        }
        sdf = TVoxel::sdfToFloat(v.sdf);
        if (sdf <= 0.1f && sdf >= -0.5f) {
            bool observed;
            sdf = readSdfInterpolated(voxels, index, p, observed);
        }
        if (sdf <= 0.f) {
            if (state == RayState::SearchSurface) {
                state = RayState::BehindSurface;
                break;
            }
            state = RayState::WrongSide;
            t += step_scale * (-sdf > 0.25f ? -sdf : 0.25f);
            continue;
        }
        state = RayState::SearchSurface;
        t += sdf * step_scale > 1.f ? sdf * step_scale : 1.f;
    }
    if (state != RayState::BehindSurface) return false;

    // Two SDF-sized corrections around the crossing, as castRay() does.
    bool observed;
    t += sdf * step_scale;
    sdf = readSdfInterpolated(voxels, index, origin + dir * t, observed);
    t += sdf * step_scale;
    hit_grid = origin + dir * t;
    return true;
}

// A surface hit (grid units) as the raycast's per-pixel outputs: world point (w = 1) and the SDF
// gradient normal (w = 1, or all zero where the gradient vanishes).
template <class TVoxel, class TIndexData>
VF_HOST_DEVICE inline void raycastHitOutputs(const TVoxel* voxels, const TIndexData& index, Vec3f hit_grid, float voxel_size_m,
                                             Vec4f& point_world, Vec4f& normal_world) {
    const Vec3f n = sdfGradientNormal(voxels, index, hit_grid);
    const Vec3f p = hit_grid * voxel_size_m;
    point_world = Vec4f{p.x, p.y, p.z, 1.f};
    normal_world = length(n) > 0.5f ? Vec4f{n.x, n.y, n.z, 1.f} : Vec4f{0.f, 0.f, 0.f, 0.f};
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
