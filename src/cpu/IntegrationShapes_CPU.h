#pragma once
// The CPU's own loop shapes of integration (engines/IntegrationEngine_Impl.h picks them when the device
// is not kOneThreadPerItem): a whole hash block or a frustum-clipped row of the dense box per element.
// The per-voxel update both devices share is in shared/Integration.h.
//
// Contract: each shape fuses every voxel bit for bit as the shared body it stands for does, in any
// frame; tests/engines/GpuShapesOnCpuTest.cpp (HashPipelineGivesTheSameTableVoxelsRaysAndRenders,
// DenseIntegrationVoxelByVoxelEqualsTheClippedRows) holds them to it.

#include "voxfuse/core/Platform.h"
#include "voxfuse/shared/Integration.h"

namespace voxfuse {

// The voxel block hash: element i is visible block i, whole (the block's entry is read once); the
// same updates as IntegrateHashVoxels, voxel by voxel. A thread takes neighbouring blocks one after the
// other, and each block's 4 KiB (s_rgb) lie wherever the allocator put them: while it fuses a block it
// prefetches the next one's voxels, row by row, and the entry of the one after, so that the loads of a
// block do not wait on memory. A row's voxel positions and depth pixels come first, in a loop the
// compiler vectorises.
template <class TVoxel>
struct IntegrateHashBlocks {
    static constexpr int kElementsPerBlock = 1;
    TVoxel* voxels;
    const HashEntry* entries;
    const int* visible_entries;
    int block_count;  // of visible_entries
    IntegrationFrame frame;

    static int elementCount(int visible_blocks) { return visible_blocks; }
    void operator()(int i) const {
        const HashEntry& e = entries[visible_entries[i]];
        TVoxel* block = voxels + (long long)e.ptr * kBlockVoxelCount;
        const Vec3i corner{e.pos.x * kBlockSide, e.pos.y * kBlockSide, e.pos.z * kBlockSide};
        // A copy the voxel stores cannot alias: byte stores may alias any member of *this, which would
        // reload every frame constant after each voxel of the block.
        const IntegrationFrame f = frame;
        const Vec3f corner_cam = blockCornerInDepthCamera(f, corner);
        if (i + 2 < block_count) VF_PREFETCH_FOR_READ(&entries[visible_entries[i + 2]]);
        const char* next_block = i + 1 < block_count
                                     ? reinterpret_cast<const char*>(
                                           voxels + (long long)entries[visible_entries[i + 1]].ptr * kBlockVoxelCount)
                                     : nullptr;
        constexpr int kRowBytes = kBlockSide * int(sizeof(TVoxel));
        for (int z = 0; z < kBlockSide; ++z)
            for (int y = 0; y < kBlockSide; ++y) {
                if (next_block != nullptr) {
                    const char* next_row = next_block + (y + z * kBlockSide) * kRowBytes;
                    VF_PREFETCH_FOR_WRITE(next_row);
                    VF_PREFETCH_FOR_WRITE(next_row + kRowBytes - 1);
                }
                const Vec3f row = blockRowOffset(f, y, z);
                TVoxel* line = block + (y + z * kBlockSide) * kBlockSide;
                float px[kBlockSide], py[kBlockSide], pz[kBlockSide];
                int pixel[kBlockSide];
                for (int x = 0; x < kBlockSide; ++x) {
                    const Vec3f p = blockVoxelInDepthCamera(f, corner_cam, row, x);
                    px[x] = p.x;
                    py[x] = p.y;
                    pz[x] = p.z;
                    pixel[x] = depthPixelOfVoxel(p, f);
                }
                for (int x = 0; x < kBlockSide; ++x)
                    integrateVoxelAtPixel(line[x], corner + Vec3i{x, y, z}, Vec3f{px[x], py[x], pz[x]}, pixel[x], f);
            }
    }
};

// The dense array, one x-row of the box per element, clipped to the frustum first (frustumRowRange):
// skipping the voxels outside the frustum is what pays on the CPU. The same updates as
// IntegrateDenseVoxel, voxel by voxel.
template <class TVoxel>
struct IntegrateDenseRow {
    TVoxel* voxels;
    PlainVoxelArray::Data index;
    Vec3i lo, hi;
    float far_m;
    IntegrationFrame frame;
    void operator()(int row) const {
        const int y = lo.y + row % (hi.y - lo.y), z = lo.z + row / (hi.y - lo.y);
        TVoxel* line = voxels + (long long)index.size.x * (y + (long long)index.size.y * z);
        int x_begin = lo.x, x_end = hi.x;
        const Vec3f row_origin = toFloat(Vec3i{0, y, z} + index.offset) * frame.voxel_size_m;
        if (!frustumRowRange(frame, row_origin, Vec3f{frame.voxel_size_m, 0.f, 0.f}, frame.near_m, far_m, x_begin,
                             x_end))
            return;
        x_begin = x_begin > lo.x ? x_begin : lo.x;
        x_end = x_end < hi.x ? x_end : hi.x;
        for (int x = x_begin; x < x_end; ++x) integrateVoxel(line[x], Vec3i{x, y, z} + index.offset, frame);
    }
};

}  // namespace voxfuse
