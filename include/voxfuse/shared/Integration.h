#pragma once
// Fusing one depth (and colour) frame into one voxel: the projective TSDF update of KinectFusion,
// as in section 4.3 of the InfiniTAM report, shared by the CPU loop and the CUDA kernel.

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/HashTableTypes.h"
#include "voxfuse/objects/Intrinsics.h"
#include "voxfuse/objects/PlainVoxelArray.h"
#include "voxfuse/shared/BlockProjection.h"
#include "voxfuse/shared/LabelFusion.h"

namespace voxfuse {

// Everything a voxel update needs from the current frame (trivially copyable: passed to kernels by value).
struct IntegrationFrame {
    Mat4f T_depth_world;  // world -> depth camera
    Intrinsics depth_intrinsics;
    const float* depth;  // metres, 0 = invalid
    Mat4f T_rgb_world;   // world -> colour camera
    Intrinsics rgb_intrinsics;
    const Vec4u8* rgb;            // nullptr when there is no colour
    const ClassId* labels;        // class per pixel of the label image; nullptr when none
    Mat4f T_label_world;          // world -> the camera that saw the labels (colour, or depth without colour)
    Intrinsics label_intrinsics;  // that camera at the label image's resolution
    LabelUpdate label_update;
    std::uint32_t label_seed;  // differs per frame: see labelRandom()
    float voxel_size_m;
    float mu_m;
    int max_weight;
    float min_depth_m, max_depth_m;  // depth samples outside are ignored
    float near_m;                    // voxels closer to the camera are not updated
    bool stop_at_max_weight;
    Vec3f voxel_step_x, voxel_step_y, voxel_step_z;  // one voxel along world x, y, z in depth camera coordinates (m)
};

// ---- A hash block's voxels in depth camera coordinates ----
// The block corner's position plus the voxel's offset in the block, in this one form on both devices:
// the CPU, which takes a block row by row, shares the corner's and the row's terms among the voxels of
// a row and still computes the bits the GPU computes voxel by voxel.

VF_HOST_DEVICE inline Vec3f blockCornerInDepthCamera(const IntegrationFrame& f, Vec3i corner) {
    return transformPoint(f.T_depth_world, toFloat(corner) * f.voxel_size_m);
}
// The offset of the row (y, z) of a block.
VF_HOST_DEVICE inline Vec3f blockRowOffset(const IntegrationFrame& f, int y, int z) {
    return f.voxel_step_y * float(y) + f.voxel_step_z * float(z);
}
VF_HOST_DEVICE inline Vec3f blockVoxelInDepthCamera(const IntegrationFrame& f, Vec3f corner_cam, Vec3f row_offset,
                                                    int x) {
    return corner_cam + (f.voxel_step_x * float(x) + row_offset);
}

// Bilinear colour lookup; false when the point falls outside the image.
VF_HOST_DEVICE inline bool sampleColorBilinear(const Vec4u8* rgb, Vec2i size, Vec2f px, Vec3f& out) {
    if (!(px.x >= 0.f && px.y >= 0.f && px.x <= float(size.x - 1) && px.y <= float(size.y - 1))) return false;
    const int x0 = int(px.x), y0 = int(px.y);
    const int x1 = x0 + 1 < size.x ? x0 + 1 : x0, y1 = y0 + 1 < size.y ? y0 + 1 : y0;
    const float fx = px.x - float(x0), fy = px.y - float(y0);
    const Vec4u8 a = rgb[x0 + y0 * size.x], b = rgb[x1 + y0 * size.x], c = rgb[x0 + y1 * size.x],
                 d = rgb[x1 + y1 * size.x];
    for (int ch = 0; ch < 3; ++ch)
        out[ch] = (1.f - fy) * ((1.f - fx) * a[ch] + fx * b[ch]) + fy * ((1.f - fx) * c[ch] + fx * d[ch]);
    return true;
}

// Restricts x to where a row of voxels p(x) = row_origin + x * step (world metres) lies inside the
// depth camera's frustum between near_m and far_m. Each image border is a linear inequality in x
// once multiplied by the (positive) depth, so the row's range is an interval; widened by one voxel.
VF_HOST_DEVICE inline bool frustumRowRange(const IntegrationFrame& f, Vec3f row_origin_world, Vec3f step_world,
                                           float near_m, float far_m, int& x_begin, int& x_end) {
    const Vec3f a = transformPoint(f.T_depth_world, row_origin_world);
    const Vec3f b = transformDirection(f.T_depth_world, step_world);
    const Intrinsics& in = f.depth_intrinsics;
    // Constraints c0 + c1 * x >= 0.
    const float c0[6] = {a.z - near_m,
                         far_m - a.z,
                         in.fx * a.x + (in.cx + 0.5f) * a.z,
                         -(in.fx * a.x + (in.cx - float(in.width) + 0.5f) * a.z),
                         in.fy * a.y + (in.cy + 0.5f) * a.z,
                         -(in.fy * a.y + (in.cy - float(in.height) + 0.5f) * a.z)};
    const float c1[6] = {b.z,
                         -b.z,
                         in.fx * b.x + (in.cx + 0.5f) * b.z,
                         -(in.fx * b.x + (in.cx - float(in.width) + 0.5f) * b.z),
                         in.fy * b.y + (in.cy + 0.5f) * b.z,
                         -(in.fy * b.y + (in.cy - float(in.height) + 0.5f) * b.z)};
    float lo = float(x_begin), hi = float(x_end);
    for (int k = 0; k < 6; ++k) {
        if (c1[k] > 0.f)
            lo = fmaxf(lo, -c0[k] / c1[k] - 1.f);
        else if (c1[k] < 0.f)
            hi = fminf(hi, -c0[k] / c1[k] + 2.f);
        else if (c0[k] < 0.f)
            return false;
    }
    if (!(lo < hi)) return false;
    x_begin = int(floorf(lo));
    x_end = int(ceilf(hi));
    return x_begin < x_end;
}

// The depth pixel a voxel at p_cam (depth camera coordinates) reads, or -1: closer than near_m, or
// outside the image. Without branches, so that the CPU computes a row of voxels' pixels in vector
// registers (a voxel behind the camera projects to garbage, which the select drops).
VF_HOST_DEVICE inline int depthPixelOfVoxel(Vec3f p_cam, const IntegrationFrame& f) {
    const int pixel = f.depth_intrinsics.nearestPixelIndex(f.depth_intrinsics.project(p_cam));
    return p_cam.z >= f.near_m ? pixel : -1;
}

// Updates `voxel` (grid position `pos`, centre at pos * voxel size, at p_cam in depth camera
// coordinates, reading depth pixel `depth_pixel` = depthPixelOfVoxel(p_cam, f)) with the frame.
// Returns eta, the measured depth minus the voxel's depth along the optical axis, or a large negative
// number when the voxel gets no update.
template <class TVoxel>
VF_HOST_DEVICE inline float integrateVoxelAtPixel(TVoxel& voxel, Vec3i pos, Vec3f p_cam, int depth_pixel,
                                                  const IntegrationFrame& f) {
    const float kNoUpdate = -1e30f;
    if (depth_pixel < 0) return kNoUpdate;

    const float depth_m = f.depth[depth_pixel];
    if (!(depth_m >= f.min_depth_m && depth_m <= f.max_depth_m)) return kNoUpdate;  // also rejects 0 and NaN

    // Behind the observed surface by more than mu: the frame says nothing about this voxel.
    const float eta = depth_m - p_cam.z;
    if (eta < -f.mu_m) return kNoUpdate;

    const int old_w = voxel.w_depth;
    if (f.stop_at_max_weight && old_w >= f.max_weight) return eta;
    const float new_sdf = eta / f.mu_m < 1.f ? eta / f.mu_m : 1.f;
    const float fused = (TVoxel::sdfToFloat(voxel.sdf) * float(old_w) + new_sdf) / float(old_w + 1);
    voxel.sdf = TVoxel::sdfFromFloat(fused);
    voxel.w_depth = (unsigned char)(old_w + 1 < f.max_weight ? old_w + 1 : f.max_weight);

    // Colour and class belong to the surface: only voxels close to the zero crossing take them.
    [[maybe_unused]] const bool near_surface = eta < 0.5f * f.mu_m && eta > -0.5f * f.mu_m;
    [[maybe_unused]] const Vec3f p_world = toFloat(pos) * f.voxel_size_m;
    if constexpr (TVoxel::hasColor) {
        if (f.rgb != nullptr && near_surface) {
            const Vec3f p_rgb = transformPoint(f.T_rgb_world, p_world);
            Vec3f c;
            if (p_rgb.z > 0.f &&
                sampleColorBilinear(f.rgb, f.rgb_intrinsics.size(), f.rgb_intrinsics.project(p_rgb), c)) {
                const int old_wc = voxel.w_color;
                // Channel by channel without operator[]: GCC reads (&x)[i] on a byte vector as out of bounds.
                auto blend = [old_wc](unsigned char old, float seen) {
                    return (unsigned char)((float(old) * float(old_wc) + seen) / float(old_wc + 1) + 0.5f);
                };
                voxel.clr = {blend(voxel.clr.x, c.x), blend(voxel.clr.y, c.y), blend(voxel.clr.z, c.z)};
                voxel.w_color = (unsigned char)(old_wc + 1 < f.max_weight ? old_wc + 1 : f.max_weight);
            }
        }
    }
    if constexpr (TVoxel::hasLabel) {
        // The class is the label image's pixel nearest to the voxel (ids are never interpolated).
        if (f.labels != nullptr && near_surface) {
            const Vec3f p_label = transformPoint(f.T_label_world, p_world);
            const int label_pixel =
                p_label.z > 0.f ? f.label_intrinsics.nearestPixelIndex(f.label_intrinsics.project(p_label)) : -1;
            const ClassId observed = label_pixel >= 0 ? f.labels[label_pixel] : kNoLabel;
            if (observed != kNoLabel)
                fuseLabel(voxel.label, voxel.w_label, observed, f.label_update, f.max_weight,
                          labelRandom(pos, f.label_seed));
        }
    }
    return eta;
}

template <class TVoxel>
VF_HOST_DEVICE inline float integrateVoxelAt(TVoxel& voxel, Vec3i pos, Vec3f p_cam, const IntegrationFrame& f) {
    return integrateVoxelAtPixel(voxel, pos, p_cam, depthPixelOfVoxel(p_cam, f), f);
}

// integrateVoxelAt() for a voxel given by its grid position alone (the dense array): placed through the
// block it would lie in under the hash, so that both indexes fuse the same bits.
template <class TVoxel>
VF_HOST_DEVICE inline float integrateVoxel(TVoxel& voxel, Vec3i pos, const IntegrationFrame& f) {
    const Vec3i in_block{pos.x & (kBlockSide - 1), pos.y & (kBlockSide - 1), pos.z & (kBlockSide - 1)};
    const Vec3f corner_cam = blockCornerInDepthCamera(f, pos - in_block);
    return integrateVoxelAt(
        voxel, pos, blockVoxelInDepthCamera(f, corner_cam, blockRowOffset(f, in_block.y, in_block.z), in_block.x), f);
}

// ---- Loop bodies of the device layers ----

// For the launchers' maxOf: the depth of pixel i when the integration uses it, else 0.
struct UsableDepth {
    const float* depth;
    float min_depth_m, max_depth_m;
    VF_HOST_DEVICE float operator()(int i) const {
        return depth[i] >= min_depth_m && depth[i] <= max_depth_m ? depth[i] : 0.f;
    }
};

// The voxel block hash: element i updates `VoxelsPerElement` consecutive voxels (a divisor of 512) of
// the visible blocks, taken in visible-list order; the CUDA layer takes a voxel per thread. The CPU
// layer takes whole blocks in its own shape (cpu/IntegrationShapes_CPU.h: IntegrateHashBlocks).
template <class TVoxel, int VoxelsPerElement>
struct IntegrateHashVoxels {
    static_assert(kBlockVoxelCount % VoxelsPerElement == 0, "elements must not straddle blocks");
    static constexpr int kElementsPerBlock = kBlockVoxelCount / VoxelsPerElement;
    TVoxel* voxels;
    const HashEntry* entries;
    const int* visible_entries;
    int block_count;  // of visible_entries
    IntegrationFrame frame;

    static int elementCount(int visible_blocks) { return visible_blocks * kElementsPerBlock; }
    VF_HOST_DEVICE void operator()(int i) const {
        const HashEntry& e = entries[visible_entries[i / kElementsPerBlock]];
        TVoxel* block = voxels + (long long)e.ptr * kBlockVoxelCount;
        const Vec3i corner{e.pos.x * kBlockSide, e.pos.y * kBlockSide, e.pos.z * kBlockSide};
        const Vec3f corner_cam = blockCornerInDepthCamera(frame, corner);
        const IntegrationFrame& f = frame;
        const int first = (i % kElementsPerBlock) * VoxelsPerElement;
        for (int v = first; v < first + VoxelsPerElement; ++v) {
            const int x = v & 7, y = (v >> 3) & 7, z = v >> 6;
            integrateVoxelAt(block[v], corner + Vec3i{x, y, z},
                             blockVoxelInDepthCamera(f, corner_cam, blockRowOffset(f, y, z), x), f);
        }
    }
};

// ---- Skipping blocks no voxel of which the frame updates (hash integration) ----
// Many voxels of the visible blocks lie more than mu behind the surface the frame sees, and
// some blocks have no depth in front of them at all: integrateVoxel() would leave all of them as they
// are. A block is skipped when the largest usable depth among the pixels its voxels can project to,
// plus mu, lies in front of its nearest voxel. The test is conservative (padded boxes, whole tiles of
// pixels), so the voxels come out bit-identical to integrating every block.

constexpr int kDepthTile = 8;  // pixels per side of a tile of the depth-maximum image

// Per tile of kDepthTile x kDepthTile pixels: the largest depth integration uses (0: none).
struct DepthMaxTiles {
    const float* depth;
    Vec2i size;  // of the depth image
    float min_depth_m, max_depth_m;
    int tiles_x;
    float* tile_max;
    VF_HOST_DEVICE void operator()(int t) const {
        const int x0 = (t % tiles_x) * kDepthTile, y0 = (t / tiles_x) * kDepthTile;
        const int x1 = x0 + kDepthTile < size.x ? x0 + kDepthTile : size.x,
                  y1 = y0 + kDepthTile < size.y ? y0 + kDepthTile : size.y;
        float m = 0.f;
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                const float d = depth[x + y * size.x];
                if (d >= min_depth_m && d <= max_depth_m && d > m) m = d;
            }
        tile_max[t] = m;
    }
};

// Per visible block k: keep[k] = 1 when some voxel of entries[visible_entries[k]] may be updated.
struct BlockNeedsIntegration {
    const HashEntry* entries;
    const int* visible_entries;
    BlockProjection projection;  // the depth camera; far_m = the largest usable depth + mu
    float mu_m;
    const float* tile_max;
    int tiles_x, tiles_y;
    unsigned char* keep;
    VF_HOST_DEVICE void operator()(int k) const {
        keep[k] = 0;
        const HashEntry& e = entries[visible_entries[k]];
        Vec2f lo, hi;
        float z_min, z_max;
        // Half a voxel of padding and a pixel of rounding each side absorb the float differences between
        // the box's corners and the voxel centres integrateVoxel() projects.
        if (!projectBlockBox({e.pos.x, e.pos.y, e.pos.z}, 0.5f, projection, lo, hi, z_min, z_max)) return;
        const Intrinsics& in = projection.intrinsics;
        const int px0 = int(floorf(fmaxf(lo.x, 0.f))) - 1, px1 = int(ceilf(fminf(hi.x, float(in.width - 1)))) + 1;
        const int py0 = int(floorf(fmaxf(lo.y, 0.f))) - 1, py1 = int(ceilf(fminf(hi.y, float(in.height - 1)))) + 1;
        const int tx0 = (px0 > 0 ? px0 : 0) / kDepthTile, tx1 = (px1 < in.width ? px1 : in.width - 1) / kDepthTile;
        const int ty0 = (py0 > 0 ? py0 : 0) / kDepthTile, ty1 = (py1 < in.height ? py1 : in.height - 1) / kDepthTile;
        float deepest = 0.f;
        for (int ty = ty0; ty <= ty1 && ty < tiles_y; ++ty)
            for (int tx = tx0; tx <= tx1 && tx < tiles_x; ++tx) deepest = fmaxf(deepest, tile_max[tx + ty * tiles_x]);
        keep[k] = deepest > 0.f && deepest + mu_m >= z_min ? 1 : 0;
    }
};

// For the launchers' selectIndices: the kept blocks.
struct BlockIsKept {
    const unsigned char* keep;
    VF_HOST_DEVICE bool operator()(int k) const { return keep[k] != 0; }
};

// Element j: out[j] = entries_list[positions[j]] (the entries of the kept blocks, in visible-list order).
struct GatherEntries {
    const int* entries_list;
    const int* positions;
    int* out;
    VF_HOST_DEVICE void operator()(int j) const { out[j] = entries_list[positions[j]]; }
};

// The dense array, one voxel per element: element i is voxel i of the box [lo, lo + box) of array
// coordinates (x fastest) starting at box slice `z_first`. For the GPU (neighbouring threads,
// neighbouring voxels).
template <class TVoxel>
struct IntegrateDenseVoxel {
    TVoxel* voxels;
    PlainVoxelArray::Data index;
    Vec3i lo, box;
    int z_first;
    IntegrationFrame frame;
    VF_HOST_DEVICE void operator()(int i) const {
        const int x = lo.x + i % box.x, y = lo.y + (i / box.x) % box.y, z = lo.z + z_first + i / (box.x * box.y);
        integrateVoxel(voxels[x + (long long)index.size.x * (y + (long long)index.size.y * z)],
                       Vec3i{x, y, z} + index.offset, frame);
    }
};

}  // namespace voxfuse
