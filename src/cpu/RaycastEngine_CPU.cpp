// CPU/OpenMP loops of the raycast engine; per-ray work is castRay() in shared/Raycast.h.

#include <cmath>

#include "voxfuse/engines/RaycastEngine.h"
#include "voxfuse/objects/PlainVoxelArray.h"
#include "voxfuse/objects/Voxel.h"
#include "voxfuse/shared/Raycast.h"
#include "voxfuse/shared/Render.h"

namespace voxfuse::cpu {
namespace {

template <class TVoxel, class TIndex>
class RaycastEngine_CPU;

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
                const Vec3f n = sdfGradientNormal(voxels, index, hit);
                const Vec3f p = hit * params.voxel_size_m;
                points[i] = Vec4f{p.x, p.y, p.z, 1.f};
                if (length(n) > 0.5f) normals[i] = Vec4f{n.x, n.y, n.z, 1.f};
            }
    }

    void render(const Scene<TVoxel, PlainVoxelArray>& scene, const RenderState& rs, RenderMode mode, Image<Vec4u8>& image) override {
        image.resize(rs.points_world.size());
        const PlainVoxelArray::Data index = scene.index().data();
        const TVoxel* voxels = scene.voxels().host();
        const float inv_voxel = 1.f / scene.params().voxel_size_m;
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
                case RenderMode::Depth: out[i] = renderDepth(transformPoint(T_camera_world, p).z, scene.params().view_frustum_max_m); break;
                case RenderMode::Color:
                    if constexpr (TVoxel::hasColor)
                        out[i] = renderColor(readColorInterpolated(voxels, index, p * inv_voxel));
                    else
                        out[i] = renderShaded(nrm, normalize(camera - p));
                    break;
            }
        }
    }
};

}  // namespace

template <class TVoxel, class TIndex>
std::unique_ptr<RaycastEngine<TVoxel, TIndex>> makeRaycastEngine() {
    return std::make_unique<RaycastEngine_CPU<TVoxel, TIndex>>();
}

template std::unique_ptr<RaycastEngine<VoxelS, PlainVoxelArray>> makeRaycastEngine<VoxelS, PlainVoxelArray>();
template std::unique_ptr<RaycastEngine<VoxelF, PlainVoxelArray>> makeRaycastEngine<VoxelF, PlainVoxelArray>();
template std::unique_ptr<RaycastEngine<VoxelSRgb, PlainVoxelArray>> makeRaycastEngine<VoxelSRgb, PlainVoxelArray>();
template std::unique_ptr<RaycastEngine<VoxelFRgb, PlainVoxelArray>> makeRaycastEngine<VoxelFRgb, PlainVoxelArray>();

}  // namespace voxfuse::cpu
