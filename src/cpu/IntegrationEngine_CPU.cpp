// CPU/OpenMP loops of the integration engine; the per-voxel update is integrateVoxel() in shared/Integration.h.

#include "voxfuse/core/Error.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/engines/EnginePairs.h"
#include "voxfuse/objects/VoxelBlockHash.h"
#include "voxfuse/objects/Voxel.h"

namespace voxfuse::cpu {
namespace {

template <class TVoxel, class TIndex>
class IntegrationEngine_CPU;

template <class TVoxel>
class IntegrationEngine_CPU<TVoxel, PlainVoxelArray> final : public IntegrationEngine<TVoxel, PlainVoxelArray> {
public:
    void integrate(Scene<TVoxel, PlainVoxelArray>& scene, const View& view, const Mat4f& T_world_camera) override {
        const PlainVoxelArray::Data index = scene.index().data();
        const std::uint32_t integration_number = scene.takeIntegrationNumber();
        Vec3i lo, hi;  // array coordinates (not offset)
        float far_m;
        if (!denseIntegrationBox(index, scene.params(), view, T_world_camera, lo, hi, far_m)) return;
        const IntegrationFrame frame = makeIntegrationFrame(scene.params(), view, T_world_camera, view.depth.host(), view.rgb.host(),
                                                            view.labels.host(), integration_number);
        TVoxel* voxels = scene.voxels().host();
        const float voxel_size = scene.params().voxel_size_m;
        const int rows = (hi.y - lo.y) * (hi.z - lo.z);
        const float near_m = kIntegrationNearM;
        const Vec3f step{voxel_size, 0.f, 0.f};
#pragma omp parallel for schedule(dynamic, 16)
        for (int row = 0; row < rows; ++row) {
            const int y = lo.y + row % (hi.y - lo.y);
            const int z = lo.z + row / (hi.y - lo.y);
            TVoxel* line = voxels + (long long)index.size.x * (y + (long long)index.size.y * z);
            int x_begin = lo.x, x_end = hi.x;
            const Vec3f row_origin = toFloat(Vec3i{0, y, z} + index.offset) * voxel_size;
            if (!frustumRowRange(frame, row_origin, step, near_m, far_m, x_begin, x_end)) continue;
            x_begin = x_begin > lo.x ? x_begin : lo.x;
            x_end = x_end < hi.x ? x_end : hi.x;
            for (int x = x_begin; x < x_end; ++x) integrateVoxel(line[x], Vec3i{x, y, z} + index.offset, frame);
        }
    }

    void resetScene(Scene<TVoxel, PlainVoxelArray>& scene) override { scene.voxels().fillHost(TVoxel::initial()); }
};

// The hash: every voxel of the blocks in the visible list, which the allocation engine built for this view.
template <class TVoxel>
class IntegrationEngine_CPU<TVoxel, VoxelBlockHash> final : public IntegrationEngine<TVoxel, VoxelBlockHash> {
public:
    void integrate(Scene<TVoxel, VoxelBlockHash>& scene, const View& view, const Mat4f& T_world_camera) override {
        const VoxelBlockHash& hash = scene.index();
        if (!hash.visibleListIsFor(T_world_camera, view.calib.depth))
            throw Error("hash integration: the visible list is not for this view (run the allocation engine on it first)");
        const IntegrationFrame frame = makeIntegrationFrame(scene.params(), view, T_world_camera, view.depth.host(), view.rgb.host(),
                                                            view.labels.host(), scene.takeIntegrationNumber());
        TVoxel* voxels = scene.voxels().host();
        const int* visible = hash.visibleEntries();
        const int count = hash.visibleCount();
#pragma omp parallel for schedule(dynamic, 8)
        for (int k = 0; k < count; ++k) {
            const HashEntry& entry = hash.entry(visible[k]);
            TVoxel* block = voxels + (long long)entry.ptr * kBlockVoxelCount;
            const Vec3i corner = Vec3i{entry.pos.x, entry.pos.y, entry.pos.z} * kBlockSide;
            for (int i = 0; i < kBlockVoxelCount; ++i) integrateVoxel(block[i], corner + Vec3i{i & 7, (i >> 3) & 7, i >> 6}, frame);
        }
    }

    // Frees every block and returns the voxel storage to its initial (empty) size.
    void resetScene(Scene<TVoxel, VoxelBlockHash>& scene) override { scene.clearVoxelBlocks(); }
};

}  // namespace

template <class TVoxel, class TIndex>
std::unique_ptr<IntegrationEngine<TVoxel, TIndex>> makeIntegrationEngine() {
    return std::make_unique<IntegrationEngine_CPU<TVoxel, TIndex>>();
}

#define VF_INSTANTIATE(TVoxel, TIndex) template std::unique_ptr<IntegrationEngine<TVoxel, TIndex>> makeIntegrationEngine<TVoxel, TIndex>();
VF_FOR_EACH_ENGINE_PAIR(VF_INSTANTIATE)
#undef VF_INSTANTIATE

}  // namespace voxfuse::cpu
