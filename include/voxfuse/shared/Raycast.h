#pragma once
// Casting one ray through the TSDF (section 4.4 of the InfiniTAM report): steps as long as the SDF
// allows (never shorter than a voxel), a trilinear refinement at the zero crossing, and no surface
// reported where a ray enters the band from behind (the InfiniTAM report's WRONG_SIDE case).

#include "voxfuse/core/Atomics.h"
#include "voxfuse/core/Math.h"
#include "voxfuse/objects/HashTableTypes.h"
#include "voxfuse/objects/Intrinsics.h"
#include "voxfuse/shared/BlockProjection.h"
#include "voxfuse/shared/ColorTrackerTerms.h"  // intensityFromRgb
#include "voxfuse/shared/LowLevel.h"
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
        if (t0 > t1) {
            const float s = t0;
            t0 = t1;
            t1 = s;
        }
        t_min = t0 > t_min ? t0 : t_min;
        t_max = t1 < t_max ? t1 : t_max;
    }
    return t_min <= t_max;
}

// The surface point near a crossing found at t (sdf <= 0 there): two SDF-sized corrections, the first
// of which goes back. Both indexes' marches end with it.
template <class TVoxel, class TIndexData>
VF_HOST_DEVICE inline Vec3f refineSurfaceCrossing(const TVoxel* voxels, const TIndexData& index, Vec3f origin,
                                                  Vec3f dir, float t, float sdf, float step_scale) {
    bool observed;
    t += sdf * step_scale;
    sdf = readSdfInterpolated(voxels, index, origin + dir * t, observed);
    t += sdf * step_scale;
    return origin + dir * t;
}

// Marches from origin + t_min * dir to origin + t_max * dir, all in grid units (dir unit length).
// `step_scale` is mu in voxels: an SDF value s (normalised to [-1, 1]) lets us step s * step_scale.
// On success writes the surface point (grid units) and returns true.
template <class TVoxel, class TIndexData>
VF_HOST_DEVICE inline bool castRay(Vec3f& hit_grid, const TVoxel* voxels, const TIndexData& index, Vec3f origin,
                                   Vec3f dir, float t_min, float t_max, float step_scale) {
    float t = t_min;
    float sdf = 1.f;
    bool seen_front = false;  // a positive (free-space) observation on this ray
    bool crossed = false;
    bool last_observed = false;
    while (t < t_max) {
        bool observed;
        const Vec3f p = origin + dir * t;
        sdf = readSdfNearest(voxels, index, p, observed);
        // An unobserved voxel met right after an observed sample (one that fell on a depth hole) takes
        // the interpolation of its observed neighbours, as in HashRayMarch. Only then: deep in unobserved
        // space (most of a dense box) the ray keeps its cheap steps.
        if (!observed && last_observed) sdf = readSdfInterpolated(voxels, index, p, observed);
        last_observed = observed;
        if (!observed) {
            // Nothing known here: a truncation band at a time. The front seen before the gap still counts,
            // as inside an allocated hash block (HashRayMarch), so that both indexes find the same surfaces;
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
    hit_grid = refineSurfaceCrossing(voxels, index, origin, dir, t, sdf, step_scale);
    return true;
}

// ---- The voxel block hash: the InfiniTAM report's state machine ----

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
        const float face = dir[a] > 0.f ? float(block[a] * kBlockSide) + float(kBlockSide) - 0.5f
                                        : float(block[a] * kBlockSide) - 0.5f;
        const float t = (face - origin[a]) / dir[a];
        t_exit = t < t_exit ? t : t_exit;
    }
    return t_exit;
}

// The march of castRay() for the voxel block hash (TIndexData: VoxelBlockHash::Data or CachedHashView): the same
// steps, thresholds and refinement inside allocated blocks, but unallocated blocks are crossed in one
// go, and a surface counts only when the ray saw its positive side after the last unallocated gap (the
// InfiniTAM report's WRONG_SIDE: the boundary between unallocated space and negative values is no surface).
// Coarse steps are whole multiples of step_scale, the step castRay() takes through unobserved space,
// and the march starts on the lattice t_anchor + k * step_scale: where the search range starts and how
// the blocks are laid out never moves the samples, so the surface found depends on the SDF alone.
//
// The march is a state advanced one step at a time, so that the CPU can take a few rays in turns:
// a step waits on its voxel load, and the steps of other rays run meanwhile (RaycastHashPixel).
struct HashRayMarch {
    Vec3f origin, dir;  // grid units, dir unit length
    float t, t_max, step_scale;
    float sdf = 1.f;
    RayState state = RayState::SearchBlockCoarse;
    bool last_observed = false;

    VF_HOST_DEVICE HashRayMarch()
        : origin{0.f, 0.f, 0.f}, dir{0.f, 0.f, 0.f}, t(0.f), t_max(0.f), step_scale(1.f) {}  // no ray: not marching
    VF_HOST_DEVICE HashRayMarch(Vec3f origin_grid, Vec3f dir_unit, float t_anchor, float t_min, float t_max_,
                                float step_scale_)
        : origin(origin_grid),
          dir(dir_unit),
          t(t_anchor + ceilf((t_min - t_anchor) / step_scale_) * step_scale_),
          t_max(t_max_),
          step_scale(step_scale_) {}

    VF_HOST_DEVICE bool marching() const { return state != RayState::BehindSurface && t < t_max; }

    // One step of the march (call while marching()).
    template <class TVoxel, class TIndexData>
    VF_HOST_DEVICE void step(const TVoxel* voxels, const TIndexData& index) {
        const Vec3f p = origin + dir * t;
        const Vec3i voxel{int(floorf(p.x + 0.5f)), int(floorf(p.y + 0.5f)), int(floorf(p.z + 0.5f))};
        bool allocated;
        const TVoxel v = readVoxel(voxels, index, voxel, allocated);
        if (!allocated) {
            last_observed = false;
            state = RayState::SearchBlockCoarse;
            const float steps = ceilf((rayBlockExit(origin, dir, blockOfVoxel(voxel)) - t) / step_scale);
            t += (steps > 1.f ? steps : 1.f) * step_scale;
            return;
        }
        if (state == RayState::SearchBlockCoarse) state = RayState::SearchBlockFine;
        if (v.w_depth == 0) {
            // An unobserved voxel met right after an observed sample (a voxel that fell on a depth
            // hole) takes the interpolation of its observed neighbours instead of skipping a band.
            // Only then, as in castRay(), so that both indexes find the same surfaces.
            bool observed = false;
            const float s = last_observed ? readSdfInterpolated(voxels, index, p, observed) : 1.f;
            last_observed = observed;
            if (!observed) {
                t += step_scale;  // unobserved voxels of an allocated block: a truncation band at a time
                return;
            }
            sdf = s;
        } else {
            last_observed = true;
            sdf = TVoxel::sdfToFloat(v.sdf);
            if (sdf <= 0.1f && sdf >= -0.5f) {
                bool observed;
                sdf = readSdfInterpolated(voxels, index, p, observed);
            }
        }
        if (sdf <= 0.f) {
            if (state == RayState::SearchSurface) {
                state = RayState::BehindSurface;
                return;
            }
            state = RayState::WrongSide;
            t += step_scale * (-sdf > 0.25f ? -sdf : 0.25f);
            return;
        }
        state = RayState::SearchSurface;
        t += sdf * step_scale > 1.f ? sdf * step_scale : 1.f;
    }

    // Once the march has stopped: false when it found no surface, else the refined surface point.
    template <class TVoxel, class TIndexData>
    VF_HOST_DEVICE bool finish(const TVoxel* voxels, const TIndexData& index, Vec3f& hit_grid) const {
        if (state != RayState::BehindSurface) return false;
        hit_grid = refineSurfaceCrossing(voxels, index, origin, dir, t, sdf, step_scale);
        return true;
    }
};

// A surface hit (grid units) as the raycast's per-pixel outputs: world point (w = 1) and, with
// `sdf_normal`, the SDF gradient normal (w = 1, or all zero where the gradient vanishes); without it
// the normal is left to NormalsFromRaycastPoints.
template <class TVoxel, class TIndexData>
VF_HOST_DEVICE inline void raycastHitOutputs(const TVoxel* voxels, const TIndexData& index, Vec3f hit_grid,
                                             float voxel_size_m, bool sdf_normal, Vec4f& point_world,
                                             Vec4f& normal_world) {
    const Vec3f p = hit_grid * voxel_size_m;
    point_world = Vec4f{p.x, p.y, p.z, 1.f};
    if (!sdf_normal) return;
    const Vec3f n = sdfGradientNormal(voxels, index, hit_grid);
    normal_world = length(n) > 0.5f ? Vec4f{n.x, n.y, n.z, 1.f} : Vec4f{0.f, 0.f, 0.f, 0.f};
}

// The map's colour at a raycast hit (world metres; p_world * inv_voxel_size in grid units) as an
// intensity in [0, 1], the luma intensityFromRgb gives a frame's pixels; -1 where none of the voxels
// around the hit saw colour. The reference the rgbd tracker aligns a frame's intensities to.
template <class TVoxel, class TIndexData>
VF_HOST_DEVICE inline float mapIntensityAt(const TVoxel* voxels, const TIndexData& index, Vec3f p_world,
                                           float inv_voxel_size) {
    if constexpr (TVoxel::hasColor) {
        bool coloured;
        const Vec3f c = readColorInterpolated(voxels, index, p_world * inv_voxel_size, coloured);
        return coloured ? intensityFromRgb(renderColor(c)) : -1.f;
    } else {
        return -1.f;
    }
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

// ---- Loop bodies of the device layers ----

// The camera rays are cast from, and the march's constants (trivially copyable).
struct RaycastCamera {
    Intrinsics intrinsics;
    Mat4f T_world_camera;
    Vec3f origin_grid;     // camera centre in grid units
    float inv_voxel_size;  // 1 / voxel size (grid units per metre)
    float step_scale;      // mu in voxels: the longest step an SDF value allows
    float voxel_size_m;
    float min_depth_m, max_depth_m;  // depth slab searched along the optical axis

    // Pixel (x, y)'s ray in world grid units (unit direction) and the ray parameter per metre of depth.
    VF_HOST_DEVICE Vec3f rayThroughPixel(int x, int y, float& t_per_depth) const {
        float distance_per_depth;
        const Vec3f dir =
            transformDirection(T_world_camera, pixelRayDirection(intrinsics, float(x), float(y), distance_per_depth));
        t_per_depth = distance_per_depth * inv_voxel_size;
        return dir;
    }
};

// Where the surface is expected along each ray: the depth of the frame just fused from the raycast's
// own pose, in an image `factor` times the raycast's resolution along each axis. A ray whose footprint
// holds depths starts `margin_m` in front of the nearest of them instead of at the start of its
// expected range: the frame saw free space up to there, and the ray no longer crosses the empty space
// between the front of its tile's blocks and the surface (often most of its steps, each a hash
// lookup that finds nothing). A surface the model holds in front of what the frame saw (something
// that has moved away, not yet carved) is stepped over. Rays without depths in their footprint search
// their whole range.
struct RaycastDepthHint {
    const float* depth_m = nullptr;  // nullptr: no hint; 0 = no depth at a pixel
    int width = 0;                   // of the hint image
    int factor = 1;                  // hint pixels per raycast pixel along each axis
    float margin_m = 0.f;

    // The depth to start searching at for raycast pixel (x, y), or 0 for the whole range.
    VF_HOST_DEVICE float searchStart(int x, int y) const {
        if (depth_m == nullptr) return 0.f;
        float nearest = 1e30f;
        for (int dy = 0; dy < factor; ++dy)
            for (int dx = 0; dx < factor; ++dx) {
                const float d = depth_m[(x * factor + dx) + (y * factor + dy) * width];
                if (d > 0.f && d < nearest) nearest = d;
            }
        return nearest < 1e30f ? nearest - margin_m : 0.f;
    }
};

// The dense array, one pixel per element: the ray clipped to the array, then castRay().
template <class TVoxel>
struct RaycastDensePixel {
    const TVoxel* voxels;
    PlainVoxelArray::Data index;
    RaycastCamera camera;
    Vec4f* points_world;
    Vec4f* normals_world;
    Vec2f* depth_range;  // set to the whole slab: the dense raycast searches all of it
    bool sdf_normals;    // normals from the SDF gradient here, or later from the points (NormalsFromRaycastPoints)
    RaycastDepthHint hint;

    VF_HOST_DEVICE void operator()(int i) const {
        const int x = i % camera.intrinsics.width, y = i / camera.intrinsics.width;
        points_world[i] = normals_world[i] = Vec4f{0.f, 0.f, 0.f, 0.f};
        depth_range[i] = Vec2f{camera.min_depth_m, camera.max_depth_m};
        float t_per_depth;
        const Vec3f dir = camera.rayThroughPixel(x, y, t_per_depth);
        float t_min = fmaxf(camera.min_depth_m, hint.searchStart(x, y)) * t_per_depth,
              t_max = camera.max_depth_m * t_per_depth;
        // The array spans voxel centres offset .. offset + size - 1.
        const Vec3f box_lo = toFloat(index.offset), box_hi = toFloat(index.offset + index.size) - Vec3f{1.f, 1.f, 1.f};
        if (!clipRayToBox(camera.origin_grid, dir, box_lo, box_hi, t_min, t_max)) return;
        Vec3f hit;
        if (!castRay(hit, voxels, index, camera.origin_grid, dir, t_min, t_max, camera.step_scale)) return;
        raycastHitOutputs(voxels, index, hit, camera.voxel_size_m, sdf_normals, points_world[i], normals_world[i]);
    }
};

// Pixels in tiles of kRayTile x kRayTile, tile after tile, rows within a tile: consecutive elements
// cast neighbouring rays, which read the same voxel blocks, while they are in a core's cache (the
// CPU takes consecutive elements on one thread) or within one warp (the GPU). A row-major order
// left a row's blocks for the next row to read again, a few hundred kilobytes later.
constexpr int kRayTile = 8;
struct TiledPixels {
    int width, height;
    VF_HOST_DEVICE int tilesX() const { return (width + kRayTile - 1) / kRayTile; }
    VF_HOST_DEVICE int elementCount() const {
        return tilesX() * ((height + kRayTile - 1) / kRayTile) * kRayTile * kRayTile;
    }
    // Element e's pixel index, or -1 for the elements of edge tiles beyond the image.
    VF_HOST_DEVICE int pixelOf(int e) const {
        const int tile = e / (kRayTile * kRayTile), within = e % (kRayTile * kRayTile);
        const int x = (tile % tilesX()) * kRayTile + within % kRayTile,
                  y = (tile / tilesX()) * kRayTile + within / kRayTile;
        return x < width && y < height ? x + y * width : -1;
    }
};

// The voxel block hash, `RaysPerElement` consecutive pixels (in TiledPixels order; a divisor of a
// tile's 64) per element: a HashRayMarch within each pixel's expected depth range, through a
// CachedHashView of its own (consecutive steps of a ray mostly stay in one block). The GPU casts one
// ray per thread; the CPU takes a few rays in turns, a step of each, so that their voxel loads (cache
// misses, most of a raycast's time) overlap instead of following one another. Every ray takes the
// same steps either way.
template <class TVoxel, int RaysPerElement>
struct RaycastHashPixel {
    static_assert(kRayTile * kRayTile % RaysPerElement == 0, "elements must not straddle tiles");
    const TVoxel* voxels;
    HashTableView table;
    RaycastCamera camera;
    const Vec2f* depth_range;
    Vec4f* points_world;
    Vec4f* normals_world;
    bool sdf_normals;  // normals from the SDF gradient here, or later from the points (NormalsFromRaycastPoints)
    RaycastDepthHint hint;
    // When not null, the map's intensity at each hit (mapIntensityAt; -1 elsewhere), read through the
    // ray's own block cache: a separate pass (RenderIntensityPixel) looked every voxel up again.
    float* intensity = nullptr;

    VF_HOST_DEVICE TiledPixels order() const { return {camera.intrinsics.width, camera.intrinsics.height}; }
    VF_HOST_DEVICE int elementCount() const { return order().elementCount() / RaysPerElement; }

    VF_HOST_DEVICE void operator()(int e) const {
        int pixel[RaysPerElement];
        HashRayMarch march[RaysPerElement];  // not marching: no pixel, or no visible block projects there
        CachedHashView view[RaysPerElement];
        for (int k = 0; k < RaysPerElement; ++k) {
            pixel[k] = order().pixelOf(e * RaysPerElement + k);
            if (pixel[k] < 0) continue;
            view[k] = CachedHashView(table);
            march[k] = startRay(pixel[k]);
        }
        for (bool any = true; any;) {
            any = false;
            for (int k = 0; k < RaysPerElement; ++k)
                if (march[k].marching()) {
                    march[k].step(voxels, view[k]);
                    any = true;
                }
        }
        for (int k = 0; k < RaysPerElement; ++k) {
            Vec3f hit;
            if (!march[k].finish(voxels, view[k], hit)) continue;
            const int i = pixel[k];
            raycastHitOutputs(voxels, view[k], hit, camera.voxel_size_m, sdf_normals, points_world[i],
                              normals_world[i]);
            if (intensity != nullptr)
                intensity[i] = mapIntensityAt(voxels, view[k], points_world[i].xyz(), camera.inv_voxel_size);
        }
    }

private:
    // Clears pixel i's outputs and starts its march (one that is not marching where no visible block
    // projects).
    VF_HOST_DEVICE HashRayMarch startRay(int i) const {
        const int x = i % camera.intrinsics.width, y = i / camera.intrinsics.width;
        points_world[i] = normals_world[i] = Vec4f{0.f, 0.f, 0.f, 0.f};
        if (intensity != nullptr) intensity[i] = -1.f;
        const float z_min = fmaxf(fmaxf(depth_range[i].x, camera.min_depth_m), hint.searchStart(x, y));
        const float z_max = fminf(depth_range[i].y, camera.max_depth_m);
        if (!(z_max > z_min)) return HashRayMarch();
        float t_per_depth;
        const Vec3f dir = camera.rayThroughPixel(x, y, t_per_depth);
        return HashRayMarch(camera.origin_grid, dir, camera.min_depth_m * t_per_depth, z_min * t_per_depth,
                            z_max * t_per_depth, camera.step_scale);
    }
};

// Normals of a raycast from its points, per pixel (after RaycastHashPixel or RaycastDensePixel without
// SDF normals): differences of neighbouring hits, as the frame's normals are made (normalFromVertexPixel),
// facing the camera. Neighbours further apart than a truncation band per pixel are on other surfaces:
// the TSDF cannot tell surfaces closer than that apart anyway. Six SDF interpolations per hit are
// the larger part of a raycast's cost; this costs a few neighbour reads.
struct NormalsFromRaycastPoints {
    const Vec4f* points_world;
    Vec2i size;
    float max_edge_m;    // a two-pixel difference larger than this is a depth edge (2 mu)
    Vec3f camera_world;  // where normals face
    Vec4f* normals_world;
    VF_HOST_DEVICE void operator()(int i) const {
        normals_world[i] = normalFromVertexPixel(points_world, size, i % size.x, i / size.x, max_edge_m, camera_world);
    }
};

// ---- Expected depth ranges from forward-projected blocks (section 4.4 of the InfiniTAM report) ----
// The image is covered by tiles of kRangeTile x kRangeTile pixels, each with a [min, max] depth.
// Every candidate block projects its box into the tile grid; the tiles it covers are split into
// fragments of up to kRangeFragment x kRangeFragment tiles (16 x 16 pixels), one element each, which
// lower each tile's min and raise its max atomically. A pixel's range is its tile's.

constexpr int kRangeTile = 4;
constexpr int kRangeFragment = 4;

// The tiles a block covers and its depth range ([z_min, z_max], padded).
struct BlockTileRect {
    int x0, y0, x1, y1;  // inclusive tile bounds; x0 > x1 when the block covers none
    float z_min, z_max;
};

struct RangeTiles {
    Vec2f* ranges;  // per tile: x = min, y = max ({1e30, -1e30} when no block covers it)
    int tiles_x, tiles_y;
};

// Per candidate block k (entry candidates[k], or entry k without a list): its tile rectangle and
// how many fragments cover it.
struct ProjectBlockToTiles {
    const HashEntry* entries;
    const int* candidates;  // the visible list, or nullptr for every entry
    BlockProjection projection;
    float near_pad_m, far_pad_m;
    RangeTiles tiles;
    BlockTileRect* rects;
    int* fragment_counts;

    VF_HOST_DEVICE void operator()(int k) const {
        BlockTileRect r{0, 0, -1, -1, 0.f, 0.f};
        fragment_counts[k] = 0;
        rects[k] = r;
        const HashEntry& e = entries[candidates ? candidates[k] : k];
        if (e.ptr < 0) return;
        Vec2f lo, hi;
        float z_lo, z_hi;
        // Boxes grow by one voxel (trilinear reads reach that far).
        if (!projectBlockBox({e.pos.x, e.pos.y, e.pos.z}, 1.f, projection, lo, hi, z_lo, z_hi)) return;
        // Pixel centres inside the projected box, clipped to the image, then their tiles.
        const Intrinsics& in = projection.intrinsics;
        const int px0 = int(ceilf(fmaxf(lo.x, 0.f))), px1 = int(floorf(fminf(hi.x, float(in.width - 1))));
        const int py0 = int(ceilf(fmaxf(lo.y, 0.f))), py1 = int(floorf(fminf(hi.y, float(in.height - 1))));
        if (px0 > px1 || py0 > py1) return;
        r = BlockTileRect{px0 / kRangeTile, py0 / kRangeTile,  px1 / kRangeTile,
                          py1 / kRangeTile, z_lo - near_pad_m, z_hi + far_pad_m};
        rects[k] = r;
        fragment_counts[k] = ((r.x1 - r.x0) / kRangeFragment + 1) * ((r.y1 - r.y0) / kRangeFragment + 1);
    }
};

// Per fragment f: finds its block (fragment_offsets is the exclusive scan of fragment_counts) and
// widens the ranges of the fragment's tiles.
struct FillRangeFragment {
    const BlockTileRect* rects;
    const int* fragment_offsets;
    int block_count;
    RangeTiles tiles;

    VF_HOST_DEVICE void operator()(int f) const {
        int lo = 0, hi = block_count - 1;  // the last block whose offset is <= f
        while (lo < hi) {
            const int mid = (lo + hi + 1) / 2;
            if (fragment_offsets[mid] <= f)
                lo = mid;
            else
                hi = mid - 1;
        }
        const BlockTileRect& r = rects[lo];
        const int index = f - fragment_offsets[lo], per_row = (r.x1 - r.x0) / kRangeFragment + 1;
        const int tx0 = r.x0 + (index % per_row) * kRangeFragment, ty0 = r.y0 + (index / per_row) * kRangeFragment;
        const int tx1 = tx0 + kRangeFragment - 1 < r.x1 ? tx0 + kRangeFragment - 1 : r.x1;
        const int ty1 = ty0 + kRangeFragment - 1 < r.y1 ? ty0 + kRangeFragment - 1 : r.y1;
        for (int ty = ty0; ty <= ty1; ++ty)
            for (int tx = tx0; tx <= tx1; ++tx) {
                Vec2f* range = &tiles.ranges[tx + ty * tiles.tiles_x];
                atomicMinFloat(&range->x, r.z_min);
                atomicMaxFloat(&range->y, r.z_max);
            }
    }
};

// Per pixel: the range of its tile, or {0, 0} where no block projects.
struct PixelRangeFromTiles {
    RangeTiles tiles;
    int width;
    Vec2f* depth_range;
    VF_HOST_DEVICE void operator()(int i) const {
        const int x = i % width, y = i / width;
        const Vec2f r = tiles.ranges[x / kRangeTile + (y / kRangeTile) * tiles.tiles_x];
        depth_range[i] = r.y > r.x ? r : Vec2f{0.f, 0.f};
    }
};

}  // namespace voxfuse
