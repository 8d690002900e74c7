#pragma once
// The raycast engine's stages, written once for both device layers: a template on the device type
// (CpuDevice or CudaDevice), instantiated by src/cpu/RaycastEngine_CPU.cpp and cuda/RaycastEngine_CUDA.cu.
// Loop bodies: shared/Raycast.h (rays, expected depth ranges) and shared/Render.h (renders); one ray
// per element on both devices (a row per element with a cache shared by its rays was no faster on the
// CPU, not worth a second shape).

#include <memory>
#include <type_traits>

#include "core/DeviceScratch.h"
#include "engines/DeviceImages.h"
#include "voxfuse/engines/RaycastEngine.h"
#include "voxfuse/objects/PlainVoxelArray.h"
#include "voxfuse/objects/VoxelBlockHash.h"
#include "voxfuse/shared/Raycast.h"
#include "voxfuse/shared/Render.h"

namespace voxfuse {

inline RaycastCamera makeRaycastCamera(const SceneParams& params, const Intrinsics& intrinsics,
                                       const Mat4f& T_world_camera) {
    const float inv_voxel = 1.f / params.voxel_size_m;
    return RaycastCamera{intrinsics,
                         T_world_camera,
                         T_world_camera.translation() * inv_voxel,
                         inv_voxel,
                         params.mu_m * inv_voxel,
                         params.voxel_size_m,
                         params.view_frustum_min_m,
                         params.view_frustum_max_m};
}

template <class TDevice, class TVoxel, class TIndex>
class RaycastEngineOn final : public RaycastEngine<TVoxel, TIndex> {
    static constexpr Device kDevice = TDevice::kind;
    static constexpr bool kHash = std::is_same<TIndex, VoxelBlockHash>::value;

public:
    void raycast(const Scene<TVoxel, TIndex>& scene, const Intrinsics& intr, const Mat4f& T_world_camera,
                 RenderState& rs, RaycastNormals normals_from, const Image<float>* depth_hint_m,
                 bool with_intensity) override {
        requireSceneOn(kDevice, scene, "the raycast engine");
        const RaycastDepthHint hint = depthHint(scene.params(), intr, depth_hint_m);
        rs.resize(intr, kDevice);
        rs.T_world_camera = T_world_camera;
        const RaycastCamera camera = makeRaycastCamera(scene.params(), intr, T_world_camera);
        Vec4f* points = rs.points_world.memory().data(kDevice);
        Vec4f* normals = rs.normals_world.memory().data(kDevice);
        Vec2f* ranges = rs.depth_range.memory().data(kDevice);
        const int pixels = intr.width * intr.height;
        const bool sdf_normals = normals_from == RaycastNormals::SdfGradient;
        bool intensity_done = false;
        if constexpr (kHash) {
            computeDepthRanges(scene, intr, T_world_camera, ranges);
            // The CPU takes a row of a ray tile, eight rays, in turns (see RaycastHashPixel); the GPU one ray per
            // thread.
            RaycastHashPixel<TVoxel, TDevice::kOneThreadPerItem ? 1 : 8> rays{
                scene.voxelData(), scene.index().data(), camera, ranges, points, normals, sdf_normals, hint};
            if (with_intensity && TVoxel::hasColor) {
                rs.intensity.resize(intr.size(), kDevice == Device::CPU, kDevice == Device::CUDA);
                rays.intensity = rs.intensity.memory().data(kDevice);
                intensity_done = true;
            }
            TDevice::parallelFor(rays.elementCount(), rays);
        } else {
            TDevice::parallelFor(pixels, RaycastDensePixel<TVoxel>{scene.voxelData(), scene.index().data(), camera,
                                                                   points, normals, ranges, sdf_normals, hint});
        }
        if (!sdf_normals)
            TDevice::parallelFor(pixels, NormalsFromRaycastPoints{points, intr.size(), 2.f * scene.params().mu_m,
                                                                  T_world_camera.translation(), normals});
        if (with_intensity && !intensity_done) renderIntensity(scene, rs, rs.intensity);
    }

    // Renders on the engine's device; the image's host copy is brought up to date for the caller.
    void render(const Scene<TVoxel, TIndex>& scene, const RenderState& rs, RenderMode mode,
                Image<Vec4u8>& image) override {
        requireSceneOn(kDevice, scene, "the raycast engine");
        if (!rs.points_world.memory().isCurrent(kDevice) || !rs.normals_world.memory().isCurrent(kDevice))
            throw DeviceError(std::string("render: the raycast was not made on ") + deviceName(kDevice));
        image.resize(rs.points_world.size(), true, kDevice == Device::CUDA);
        const SceneParams& params = scene.params();
        const RenderRaycastPixel<TVoxel, typename TIndex::Data> pixel{scene.voxelData(),
                                                                      scene.index().data(),
                                                                      mode,
                                                                      1.f / params.voxel_size_m,
                                                                      params.view_frustum_max_m,
                                                                      rs.T_world_camera.translation(),
                                                                      rigidInverse(rs.T_world_camera),
                                                                      rs.points_world.memory().data(kDevice),
                                                                      rs.normals_world.memory().data(kDevice),
                                                                      image.memory().data(kDevice)};
        TDevice::parallelFor(int(image.pixelCount()), pixel);
        image.memory().updateHost();
    }

    void renderIntensity(const Scene<TVoxel, TIndex>& scene, const RenderState& rs, Image<float>& intensity) override {
        requireSceneOn(kDevice, scene, "the raycast engine");
        if (!rs.points_world.memory().isCurrent(kDevice))
            throw DeviceError(std::string("renderIntensity: the raycast was not made on ") + deviceName(kDevice));
        intensity.resize(rs.points_world.size(), kDevice == Device::CPU, kDevice == Device::CUDA);
        const RenderIntensityPixel<TVoxel, typename TIndex::Data> pixel{
            scene.voxelData(), scene.index().data(), 1.f / scene.params().voxel_size_m,
            rs.points_world.memory().data(kDevice), intensity.memory().data(kDevice)};
        TDevice::parallelFor(int(intensity.pixelCount()), pixel);
    }

private:
    RaycastDepthHint depthHint(const SceneParams& params, const Intrinsics& intr, const Image<float>* depth_m) {
        if (depth_m == nullptr || depth_m->empty()) return RaycastDepthHint{};
        // A raycast of a downsampled camera (Intrinsics::downsampled) drops a last odd row or column.
        const int factor = depth_m->width() / intr.width;
        if (factor < 1 || depth_m->height() / intr.height != factor)
            throw Error("raycast: a depth hint of " + std::to_string(depth_m->width()) + "x" +
                        std::to_string(depth_m->height()) + " is not an integer multiple of the " +
                        std::to_string(intr.width) + "x" + std::to_string(intr.height) + " raycast");
        return RaycastDepthHint{imageOn(kDevice, *depth_m, hint_staging_), depth_m->width(), factor, 2.f * params.mu_m};
    }

    // Per pixel [min, max] depth of the blocks that project onto it ({0, 0} where none does): the visible
    // list when it was built for this view, else every allocated block in the frustum (other viewpoints).
    // Ranges grow by one voxel in front and by mu behind (the longest ray step) so that a crossing near
    // a block's far face is not stepped over.
    void computeDepthRanges(const Scene<TVoxel, TIndex>& scene, const Intrinsics& intr, const Mat4f& T_world_camera,
                            Vec2f* ranges) {
        const VoxelBlockHash& hash = scene.index();
        const SceneParams& params = scene.params();
        const bool use_visible_list = hash.visibleListCovers(T_world_camera, intr);
        const int candidates = use_visible_list ? hash.visibleCount() : hash.entryCount();
        const RangeTiles tiles{nullptr, (intr.width + kRangeTile - 1) / kRangeTile,
                               (intr.height + kRangeTile - 1) / kRangeTile};
        grow(tile_ranges_, std::size_t(tiles.tiles_x) * std::size_t(tiles.tiles_y));
        tile_ranges_.fill(kDevice, Vec2f{1e30f, -1e30f}, 0, std::size_t(tiles.tiles_x) * std::size_t(tiles.tiles_y));
        RangeTiles t = tiles;
        t.ranges = tile_ranges_.data(kDevice);
        if (candidates > 0) {
            grow(rects_, std::size_t(candidates));
            grow(fragments_, std::size_t(candidates));
            const BlockProjection projection{rigidInverse(T_world_camera), intr, params.voxel_size_m,
                                             params.view_frustum_min_m, params.view_frustum_max_m};
            TDevice::parallelFor(
                candidates, ProjectBlockToTiles{hash.data().entries, use_visible_list ? hash.visibleEntries() : nullptr,
                                                projection, params.voxel_size_m, params.mu_m, t, rects_.data(kDevice),
                                                fragments_.data(kDevice)});
            const int fragment_count =
                TDevice::exclusiveScan(fragments_.data(kDevice), fragments_.data(kDevice), candidates, scratch_);
            TDevice::parallelFor(fragment_count,
                                 FillRangeFragment{rects_.data(kDevice), fragments_.data(kDevice), candidates, t});
        }
        TDevice::parallelFor(intr.width * intr.height, PixelRangeFromTiles{t, intr.width, ranges});
    }

    template <class T>
    static void grow(MemoryBlock<T>& block, std::size_t count) {
        if (block.size() < count) block.allocate(count, kDevice == Device::CPU, kDevice == Device::CUDA);
    }

    DeviceScratch scratch_{kDevice};
    MemoryBlock<float> hint_staging_;  // the hint's copy on kDevice, when it is not current there
    MemoryBlock<Vec2f> tile_ranges_;
    MemoryBlock<BlockTileRect> rects_;
    MemoryBlock<int> fragments_;
};

template <class TDevice, class TVoxel, class TIndex>
std::unique_ptr<RaycastEngine<TVoxel, TIndex>> makeRaycastEngineOn() {
    return std::make_unique<RaycastEngineOn<TDevice, TVoxel, TIndex>>();
}

}  // namespace voxfuse
