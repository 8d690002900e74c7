// CPU/OpenMP loops of the raycast engine; per-ray work is castRay() in shared/Raycast.h.

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "voxfuse/engines/RaycastEngine.h"
#include "voxfuse/engines/EnginePairs.h"
#include "voxfuse/objects/PlainVoxelArray.h"
#include "voxfuse/objects/VoxelBlockHash.h"
#include "voxfuse/objects/Voxel.h"
#include "voxfuse/shared/BlockProjection.h"
#include "voxfuse/shared/Raycast.h"
#include "voxfuse/shared/Render.h"

namespace voxfuse::cpu {
namespace {

template <class TVoxel, class TIndex>
class RaycastEngine_CPU;

// An RGBA image of a raycast; the voxels are read only for RenderMode::Color and RenderMode::Class.
template <class TVoxel, class TIndexData>
void renderRaycast(const TVoxel* voxels, const TIndexData& index, const SceneParams& params, const RenderState& rs, RenderMode mode,
                   Image<Vec4u8>& image) {
    image.resize(rs.points_world.size());
    const float inv_voxel = 1.f / params.voxel_size_m;
    const Vec3f camera = rs.T_world_camera.translation();
    const Mat4f T_camera_world = rigidInverse(rs.T_world_camera);
    const Vec4f* points = rs.points_world.host();
    const Vec4f* normals = rs.normals_world.host();
    Vec4u8* out = image.host();
    const int n = int(image.pixelCount());
#pragma omp parallel for schedule(static)
    for (int i = 0; i < n; ++i) {
        if (points[i].w <= 0.f) {
            out[i] = kBackground;
            continue;
        }
        const Vec3f p = points[i].xyz(), nrm = normals[i].xyz();
        switch (mode) {
            case RenderMode::Shaded: out[i] = renderShaded(nrm, normalize(camera - p)); break;
            case RenderMode::Normals: out[i] = renderNormal(nrm); break;
            case RenderMode::Depth: out[i] = renderDepth(transformPoint(T_camera_world, p).z, params.view_frustum_max_m); break;
            case RenderMode::Color:
                if constexpr (TVoxel::hasColor)
                    out[i] = renderColor(readColorInterpolated(voxels, index, p * inv_voxel));
                else
                    out[i] = renderShaded(nrm, normalize(camera - p));
                break;
            case RenderMode::Class:
                if constexpr (TVoxel::hasLabel)
                    out[i] = renderClass(readLabelNearest(voxels, index, p * inv_voxel), nrm, normalize(camera - p));
                else
                    out[i] = renderShaded(nrm, normalize(camera - p));
                break;
        }
    }
}

template <class TVoxel>
class RaycastEngine_CPU<TVoxel, PlainVoxelArray> final : public RaycastEngine<TVoxel, PlainVoxelArray> {
public:
    void raycast(const Scene<TVoxel, PlainVoxelArray>& scene, const Intrinsics& intr, const Mat4f& T_world_camera,
                 RenderState& rs) override {
        rs.resize(intr);
        rs.T_world_camera = T_world_camera;
        const PlainVoxelArray::Data index = scene.index().data();
        const TVoxel* voxels = scene.voxels().host();
        const SceneParams& params = scene.params();
        const float inv_voxel = 1.f / params.voxel_size_m;
        const float step_scale = params.mu_m * inv_voxel;
        const Vec3f origin = transformPoint(T_world_camera, Vec3f{0.f, 0.f, 0.f}) * inv_voxel;
        // The array spans voxel centres offset .. offset + size - 1; rays are clipped to it.
        const Vec3f box_lo = toFloat(index.offset), box_hi = toFloat(index.offset + index.size) - Vec3f{1.f, 1.f, 1.f};
        Vec4f* points = rs.points_world.host();
        Vec4f* normals = rs.normals_world.host();
        Vec2f* ranges = rs.depth_range.host();

#pragma omp parallel for schedule(dynamic, 4)
        for (int y = 0; y < intr.height; ++y)
            for (int x = 0; x < intr.width; ++x) {
                const int i = x + y * intr.width;
                points[i] = normals[i] = Vec4f{0.f, 0.f, 0.f, 0.f};
                ranges[i] = Vec2f{params.view_frustum_min_m, params.view_frustum_max_m};
                float distance_per_depth;
                const Vec3f dir = transformDirection(T_world_camera, pixelRayDirection(intr, float(x), float(y), distance_per_depth));
                float t_min = params.view_frustum_min_m * distance_per_depth * inv_voxel;
                float t_max = params.view_frustum_max_m * distance_per_depth * inv_voxel;
                if (!clipRayToBox(origin, dir, box_lo, box_hi, t_min, t_max)) continue;
                Vec3f hit;
                if (!castRay(hit, voxels, index, origin, dir, t_min, t_max, step_scale)) continue;
                raycastHitOutputs(voxels, index, hit, params.voxel_size_m, points[i], normals[i]);
            }
    }

    void render(const Scene<TVoxel, PlainVoxelArray>& scene, const RenderState& rs, RenderMode mode, Image<Vec4u8>& image) override {
        renderRaycast(scene.voxels().host(), scene.index().data(), scene.params(), rs, mode, image);
    }
};

// The hash: rays search only the depth ranges where visible blocks project (report, section 4.4), and
// castRayHash() crosses unallocated blocks in one step each.
template <class TVoxel>
class RaycastEngine_CPU<TVoxel, VoxelBlockHash> final : public RaycastEngine<TVoxel, VoxelBlockHash> {
public:
    void raycast(const Scene<TVoxel, VoxelBlockHash>& scene, const Intrinsics& intr, const Mat4f& T_world_camera,
                 RenderState& rs) override {
        rs.resize(intr);
        rs.T_world_camera = T_world_camera;
        computeDepthRanges(scene, intr, T_world_camera, rs.depth_range);

        const VoxelBlockHash::Data index = scene.index().data();
        const TVoxel* voxels = scene.voxels().host();
        const SceneParams& params = scene.params();
        const float inv_voxel = 1.f / params.voxel_size_m;
        const float step_scale = params.mu_m * inv_voxel;
        const Vec3f origin = transformPoint(T_world_camera, Vec3f{0.f, 0.f, 0.f}) * inv_voxel;
        Vec4f* points = rs.points_world.host();
        Vec4f* normals = rs.normals_world.host();
        const Vec2f* ranges = rs.depth_range.host();

#pragma omp parallel for schedule(dynamic, 4)
        for (int y = 0; y < intr.height; ++y) {
            const CachedHashView view(index);  // one per thread and row: the table does not change here
            for (int x = 0; x < intr.width; ++x) {
                const int i = x + y * intr.width;
                points[i] = normals[i] = Vec4f{0.f, 0.f, 0.f, 0.f};
                const float z_min = std::max(ranges[i].x, params.view_frustum_min_m);
                const float z_max = std::min(ranges[i].y, params.view_frustum_max_m);
                if (!(z_max > z_min)) continue;  // no visible block projects here
                float distance_per_depth;
                const Vec3f dir = transformDirection(T_world_camera, pixelRayDirection(intr, float(x), float(y), distance_per_depth));
                Vec3f hit;
                const float t_scale = distance_per_depth * inv_voxel;  // depth (m) -> ray parameter (voxels)
                if (!castRayHash(hit, voxels, view, origin, dir, params.view_frustum_min_m * t_scale, z_min * t_scale, z_max * t_scale,
                                 step_scale))
                    continue;
                raycastHitOutputs(voxels, view, hit, params.voxel_size_m, points[i], normals[i]);
            }
        }
    }

    void render(const Scene<TVoxel, VoxelBlockHash>& scene, const RenderState& rs, RenderMode mode, Image<Vec4u8>& image) override {
        renderRaycast(scene.voxels().host(), scene.index().data(), scene.params(), rs, mode, image);
    }

private:
    // Pixels are grouped in tiles of kTile x kTile for the forward projection (report, section 4.4): the
    // range of a tile bounds the ranges of its pixels, at 1/16 of the writes.
    static constexpr int kTile = 4;

    // Per pixel [min, max] depth of the blocks that project onto it ({0, 0} where none does): the visible
    // list when it was built for this view, else every allocated block in the frustum (other viewpoints).
    // Races: each thread projects its share of the blocks into its own tile image; a min/max reduction
    // over the thread images follows.
    void computeDepthRanges(const Scene<TVoxel, VoxelBlockHash>& scene, const Intrinsics& intr, const Mat4f& T_world_camera,
                            Image<Vec2f>& depth_range) {
        const VoxelBlockHash& hash = scene.index();
        const SceneParams& params = scene.params();
        const bool use_visible_list = hash.visibleListIsFor(T_world_camera, intr);
        const int candidates = use_visible_list ? hash.visibleCount() : hash.entryCount();
        // Boxes grow by one voxel (trilinear reads reach that far); ranges by one voxel in front and by
        // mu behind (the longest ray step) so that a crossing near a block's far face is not stepped over.
        const BlockProjection projection{rigidInverse(T_world_camera), intr, params.voxel_size_m, params.view_frustum_min_m,
                                         params.view_frustum_max_m};
        const float near_pad = params.voxel_size_m, far_pad = params.mu_m;
        const int tiles_x = (intr.width + kTile - 1) / kTile, tiles_y = (intr.height + kTile - 1) / kTile;
        const std::size_t tile_count = std::size_t(tiles_x) * std::size_t(tiles_y);
        const int threads = omp_get_max_threads();
        tile_ranges_.assign(tile_count * std::size_t(threads), Vec2f{1e30f, -1e30f});

#pragma omp parallel
        {
            Vec2f* tiles = tile_ranges_.data() + tile_count * std::size_t(omp_get_thread_num());
#pragma omp for schedule(dynamic, 64)
            for (int k = 0; k < candidates; ++k) {
                const HashEntry& e = hash.entry(use_visible_list ? hash.visibleEntries()[k] : k);
                if (e.ptr < 0) continue;
                Vec2f lo, hi;
                float z_lo, z_hi;
                if (!projectBlockBox({e.pos.x, e.pos.y, e.pos.z}, 1.f, projection, lo, hi, z_lo, z_hi)) continue;
                // Pixel centres inside the projected box, clipped to the image, then their tiles.
                const int x0 = std::max(0, int(std::ceil(lo.x))), x1 = std::min(intr.width - 1, int(std::floor(hi.x)));
                const int y0 = std::max(0, int(std::ceil(lo.y))), y1 = std::min(intr.height - 1, int(std::floor(hi.y)));
                if (x0 > x1 || y0 > y1) continue;
                z_lo -= near_pad;
                z_hi += far_pad;
                for (int ty = y0 / kTile; ty <= y1 / kTile; ++ty)
                    for (int tx = x0 / kTile; tx <= x1 / kTile; ++tx) {
                        Vec2f& r = tiles[tx + ty * tiles_x];
                        r.x = std::min(r.x, z_lo);
                        r.y = std::max(r.y, z_hi);
                    }
            }
        }
        for (int t = 1; t < threads; ++t)
            for (std::size_t i = 0; i < tile_count; ++i) {
                const Vec2f other = tile_ranges_[tile_count * std::size_t(t) + i];
                tile_ranges_[i] = Vec2f{std::min(tile_ranges_[i].x, other.x), std::max(tile_ranges_[i].y, other.y)};
            }
        Vec2f* out = depth_range.host();
        for (int y = 0; y < intr.height; ++y)
            for (int x = 0; x < intr.width; ++x) {
                const Vec2f r = tile_ranges_[std::size_t(x / kTile + (y / kTile) * tiles_x)];
                out[x + y * intr.width] = r.y > r.x ? r : Vec2f{0.f, 0.f};
            }
    }

    std::vector<Vec2f> tile_ranges_;  // per thread, tiles_x * tiles_y each
};

}  // namespace

template <class TVoxel, class TIndex>
std::unique_ptr<RaycastEngine<TVoxel, TIndex>> makeRaycastEngine() {
    return std::make_unique<RaycastEngine_CPU<TVoxel, TIndex>>();
}

#define VF_INSTANTIATE(TVoxel, TIndex) template std::unique_ptr<RaycastEngine<TVoxel, TIndex>> makeRaycastEngine<TVoxel, TIndex>();
VF_FOR_EACH_ENGINE_PAIR(VF_INSTANTIATE)
#undef VF_INSTANTIATE

}  // namespace voxfuse::cpu
