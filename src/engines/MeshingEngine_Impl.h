#pragma once
// The meshing engine's stages, written once for both device layers: a template on the device type
// (CpuDevice or CudaDevice), instantiated by src/cpu/MeshingEngine_CPU.cpp and cuda/MeshingEngine_CUDA.cu.
// Loop bodies: shared/MeshBlocks.h (the block list, which blocks can hold surface) and shared/Meshing.h
// (count and emit, one team per block). On the GPU everything up to the finished mesh stays there and
// only the mesh comes down.
//
//   list the blocks (hash: allocated entries sorted by Morton code) -> signs per row of voxels and block
//   -> select the blocks that may hold surface -> count per block -> scan -> emit per block

#include <climits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "core/DeviceScratch.h"
#include "engines/DeviceImages.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/MeshingEngine.h"
#include "voxfuse/objects/PlainVoxelArray.h"
#include "voxfuse/objects/VoxelBlockHash.h"
#include "voxfuse/shared/MeshBlocks.h"
#include "voxfuse/shared/Meshing.h"

namespace voxfuse {

template <class TDevice, class TVoxel, class TIndex>
class MeshingEngineOn final : public MeshingEngine<TVoxel, TIndex> {
    static constexpr Device kDevice = TDevice::kind;
    static constexpr bool kHash = std::is_same<TIndex, VoxelBlockHash>::value;

    // The caller's arrays (host memory).
    struct HostSurface {
        std::vector<Vec3f>& positions;
        std::vector<Vec3f>& normals;
        std::vector<Vec3u8>& colors;
        std::vector<ClassId>& labels;
        std::vector<Vec3i>* triangles;  // nullptr: vertices only
    };

public:
    void extractMesh(const Scene<TVoxel, TIndex>& scene, Mesh& mesh) override {
        mesh.clear();
        extract(scene, {mesh.vertices, mesh.normals, mesh.colors, mesh.labels, &mesh.triangles});
    }
    void extractPointCloud(const Scene<TVoxel, TIndex>& scene, PointCloud& cloud) override {
        cloud.clear();
        extract(scene, {cloud.points, cloud.normals, cloud.colors, cloud.labels, nullptr});
    }

private:
    void extract(const Scene<TVoxel, TIndex>& scene, HostSurface out) {
        requireSceneOn(kDevice, scene, "the meshing engine");
        if constexpr (kHash)
            run(listHashBlocks(scene), scene.params().voxel_size_m, out);
        else
            run(meshing::DenseMeshBlocks<TVoxel>::make(scene.index().data(), scene.voxelData()),
                scene.params().voxel_size_m, out);
    }

    meshing::HashMeshBlocks<TVoxel> listHashBlocks(const Scene<TVoxel, VoxelBlockHash>& scene) {
        const VoxelBlockHash& hash = scene.index();
        const HashTableView view = hash.data();
        grow(entry_ids_, std::size_t(hash.entryCount()));
        const int count = TDevice::selectIndices(hash.entryCount(), meshing::EntryHasVoxelBlock{view.entries},
                                                 entry_ids_.data(kDevice), scratch_);
        grow(codes_, std::size_t(count));
        TDevice::parallelFor(count,
                             meshing::MortonCodeOfEntry{view.entries, entry_ids_.data(kDevice), codes_.data(kDevice)});
        // A hash holds each block once, so every code is distinct; a repeat means a damaged table, whose
        // surface would come out twice (and the lists below would be read past what sortUnique kept).
        const int distinct = TDevice::sortUnique(codes_.data(kDevice), count, scratch_);
        if (distinct != count)
            throw Error("meshing: the hash table holds " + std::to_string(count - distinct) + " of its " +
                        std::to_string(count) + " blocks more than once (a damaged table)");
        grow(positions_, std::size_t(count));
        grow(ptrs_, std::size_t(count));
        // Only blocks in the list are ever looked up: the entries of other voxel blocks need no value.
        grow(list_index_of_ptr_, std::size_t(hash.blockCapacity()));
        TDevice::parallelFor(count, meshing::ListHashBlock{view, codes_.data(kDevice), positions_.data(kDevice),
                                                           ptrs_.data(kDevice), list_index_of_ptr_.data(kDevice)});
        return {
            view, scene.voxelData(), positions_.data(kDevice), ptrs_.data(kDevice), list_index_of_ptr_.data(kDevice),
            count};
    }

    template <class TBlocks>
    void run(const TBlocks& blocks, float voxel_size_m, HostSurface out) {
        using namespace meshing;
        const int block_count = blocks.count();
        grow(row_signs_, std::size_t(block_count) * kRowsPerBlock);
        grow(signs_, std::size_t(block_count));
        TDevice::parallelFor(block_count * kRowsPerBlock,
                             FindRowSigns<TVoxel, TBlocks>{blocks, row_signs_.data(kDevice)});
        TDevice::parallelFor(block_count, SummariseBlockSigns{row_signs_.data(kDevice), signs_.data(kDevice)});
        grow(meshed_, std::size_t(block_count));
        const int meshed = TDevice::selectIndices(
            block_count, BlockMayHoldSurface<TBlocks>{blocks, signs_.data(kDevice)}, meshed_.data(kDevice), scratch_);
        if (meshed == 0) return;
        grow(slot_of_block_, std::size_t(block_count));
        slot_of_block_.fill(kDevice, -1, 0, std::size_t(block_count));
        TDevice::parallelFor(meshed, SlotOfMeshedBlock{meshed_.data(kDevice), slot_of_block_.data(kDevice)});

        const std::size_t row_count = std::size_t(meshed) * kBlockRows;
        grow(neighbours_, std::size_t(meshed) * 27);
        grow(row_edges_, row_count);
        grow(row_first_vertex_, row_count);
        grow(row_first_triangle_, row_count);
        grow(vertex_count_, std::size_t(meshed));
        grow(triangle_count_, std::size_t(meshed));
        const MeshedBlockRows rows{neighbours_.data(kDevice),       row_edges_.data(kDevice),
                                   row_first_vertex_.data(kDevice), row_first_triangle_.data(kDevice),
                                   vertex_count_.data(kDevice),     triangle_count_.data(kDevice)};
        const bool with_triangles = out.triangles != nullptr;
        TDevice::template parallelForTeams<CountShared>(
            meshed,
            CountBlockSurface<TBlocks>{blocks, row_signs_.data(kDevice), meshed_.data(kDevice), rows, with_triangles});

        // The scans run in place: the counts become each block's first vertex and triangle.
        const long long vertex_total =
            TDevice::exclusiveScan(vertex_count_.data(kDevice), vertex_count_.data(kDevice), meshed, scratch_);
        const long long triangle_total =
            TDevice::exclusiveScan(triangle_count_.data(kDevice), triangle_count_.data(kDevice), meshed, scratch_);
        if (vertex_total > INT_MAX)
            throw Error("meshing: the surface has " + std::to_string(vertex_total) +
                        " vertices, more than a mesh's int indices address (2^31 - 1)");

        out.positions.resize(std::size_t(vertex_total));
        out.normals.resize(std::size_t(vertex_total));
        out.colors.resize(TVoxel::hasColor ? std::size_t(vertex_total) : 0);
        out.labels.resize(TVoxel::hasLabel ? std::size_t(vertex_total) : 0);
        if (with_triangles) out.triangles->resize(std::size_t(triangle_total));
        // The emit pass writes into the caller's arrays on the CPU, into buffers of this mesh's size on
        // the GPU (freed when it has come down: between calls meshing holds only its work arrays).
        DeviceSurface on_gpu;
        SurfaceOutput target{out.positions.data(),
                             out.normals.data(),
                             out.colors.data(),
                             out.labels.data(),
                             with_triangles ? out.triangles->data() : nullptr,
                             nullptr};
        if constexpr (kDevice == Device::CUDA) target = on_gpu.allocate(out);
        grow(unresolved_, 1);
        unresolved_.fill(kDevice, 0, 0, 1);
        target.unresolved_corners = unresolved_.data(kDevice);
        TDevice::template parallelForTeams<EmitShared<TVoxel>>(
            meshed, EmitBlockSurface<TVoxel, TBlocks>{blocks, meshed_.data(kDevice), slot_of_block_.data(kDevice), rows,
                                                      vertex_count_.data(kDevice), triangle_count_.data(kDevice),
                                                      voxel_size_m, target});
        const int unresolved = TDevice::read(unresolved_.data(kDevice), scratch_);
        if (unresolved > 0)
            throw Error("meshing: " + std::to_string(unresolved) +
                        " triangle corners refer to no vertex (the scene changed during meshing?)");
        if constexpr (kDevice == Device::CUDA) on_gpu.download(out);
    }

    // The GPU's copy of the output, sized like the caller's arrays.
    struct DeviceSurface {
        MemoryBlock<Vec3f> positions, normals;
        MemoryBlock<Vec3u8> colors;
        MemoryBlock<ClassId> labels;
        MemoryBlock<Vec3i> triangles;

        meshing::SurfaceOutput allocate(const HostSurface& out) {
            positions.allocate(out.positions.size(), false, true);
            normals.allocate(out.normals.size(), false, true);
            colors.allocate(out.colors.size(), false, true);
            labels.allocate(out.labels.size(), false, true);
            if (out.triangles) triangles.allocate(out.triangles->size(), false, true);
            return {positions.device(),
                    normals.device(),
                    colors.device(),
                    labels.device(),
                    out.triangles ? triangles.device() : nullptr,
                    nullptr};
        }
        void download(HostSurface& out) const {
            positions.readRange(Device::CUDA, 0, out.positions.data(), out.positions.size());
            normals.readRange(Device::CUDA, 0, out.normals.data(), out.normals.size());
            colors.readRange(Device::CUDA, 0, out.colors.data(), out.colors.size());
            labels.readRange(Device::CUDA, 0, out.labels.data(), out.labels.size());
            if (out.triangles) triangles.readRange(Device::CUDA, 0, out.triangles->data(), out.triangles->size());
        }
    };

    // Work arrays grow and are kept between calls (about 130 bytes per block and 640 per block with surface).
    template <class T>
    static void grow(MemoryBlock<T>& block, std::size_t count) {
        if (block.size() < count) block.allocate(count + count / 4, kDevice == Device::CPU, kDevice == Device::CUDA);
    }
    DeviceScratch scratch_{kDevice};
    MemoryBlock<int> entry_ids_, ptrs_, list_index_of_ptr_, meshed_, slot_of_block_, neighbours_;
    MemoryBlock<std::uint64_t> codes_;
    MemoryBlock<Vec3i> positions_;
    MemoryBlock<meshing::RowSigns> row_signs_;
    MemoryBlock<std::uint8_t> signs_;
    MemoryBlock<unsigned> row_edges_;
    MemoryBlock<std::uint16_t> row_first_vertex_, row_first_triangle_;
    MemoryBlock<long long> vertex_count_, triangle_count_;
    MemoryBlock<int> unresolved_;
};

template <class TDevice, class TVoxel, class TIndex>
std::unique_ptr<MeshingEngine<TVoxel, TIndex>> makeMeshingEngineOn() {
    return std::make_unique<MeshingEngineOn<TDevice, TVoxel, TIndex>>();
}

}  // namespace voxfuse
