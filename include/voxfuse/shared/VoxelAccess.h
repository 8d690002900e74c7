#pragma once
// Reading voxels through an index, for one element at a time. Each index type provides
// readVoxel(voxels, index_data, grid_position, found); the interpolating readers below work for any
// index that does.

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/ClassLabel.h"
#include "voxfuse/objects/PlainVoxelArray.h"
#include "voxfuse/shared/HashAccess.h"  // readVoxel() for VoxelBlockHash

namespace voxfuse {

// Linear offset of a grid position in a dense array, or -1 when outside it.
VF_HOST_DEVICE inline long long denseVoxelOffset(const PlainVoxelArray::Data& index, Vec3i p) {
    p -= index.offset;
    if (p.x < 0 || p.y < 0 || p.z < 0 || p.x >= index.size.x || p.y >= index.size.y || p.z >= index.size.z) return -1;
    return p.x + (long long)index.size.x * (p.y + (long long)index.size.y * p.z);
}

// `found` is false outside the array (the returned voxel is then TVoxel::initial()).
template <class TVoxel>
VF_HOST_DEVICE inline TVoxel readVoxel(const TVoxel* voxels, const PlainVoxelArray::Data& index, Vec3i p, bool& found) {
    const long long i = denseVoxelOffset(index, p);
    found = i >= 0;
    return found ? voxels[i] : TVoxel::initial();
}

// SDF of the voxel nearest to `p` (grid units). `observed` is false where no depth was ever fused.
template <class TVoxel, class TIndexData>
VF_HOST_DEVICE inline float readSdfNearest(const TVoxel* voxels, const TIndexData& index, Vec3f p, bool& observed) {
    bool found;
    const TVoxel v = readVoxel(voxels, index,
                               Vec3i{int(floorf(p.x + 0.5f)), int(floorf(p.y + 0.5f)), int(floorf(p.z + 0.5f))}, found);
    observed = found && v.w_depth > 0;
    return TVoxel::sdfToFloat(v.sdf);
}

// The eight voxels of the cell whose lowest corner is `base`: corner k at base + (k & 1, (k >> 1) & 1,
// k >> 2), found[k] false where no voxel is stored.
template <class TVoxel, class TIndexData>
VF_HOST_DEVICE inline void readCellVoxels(const TVoxel* voxels, const TIndexData& index, Vec3i base, TVoxel v[8],
                                          bool found[8]) {
    for (int k = 0; k < 8; ++k)
        v[k] = readVoxel(voxels, index, base + Vec3i{k & 1, (k >> 1) & 1, (k >> 2) & 1}, found[k]);
}

// The same through a cached hash view: each block the cell touches is looked up once (a cell mostly
// lies in one block; one lookup per corner would alternate the view's cache between two blocks
// where it straddles them). The cell's own block is looked up last, so the cache keeps it for the
// next read along a ray.
template <class TVoxel>
VF_HOST_DEVICE inline void readCellVoxels(const TVoxel* voxels, const CachedHashView& view, Vec3i base, TVoxel v[8],
                                          bool found[8]) {
    const Vec3i block = blockOfVoxel(base);
    // Bit a set: the cell's upper corners along axis a lie in the next block.
    const int crossing = ((base.x & 7) == 7 ? 1 : 0) | ((base.y & 7) == 7 ? 2 : 0) | ((base.z & 7) == 7 ? 4 : 0);
    int ptr[8];
    for (int b = 7; b >= 0; --b)
        if ((b & ~crossing) == 0) ptr[b] = view.voxelBlock(block + Vec3i{b & 1, (b >> 1) & 1, (b >> 2) & 1});
    for (int k = 0; k < 8; ++k) {
        const int p = ptr[k & crossing];
        found[k] = p >= 0;
        v[k] = found[k]
                   ? voxels[p * kBlockVoxelCount + voxelIndexInBlock(base + Vec3i{k & 1, (k >> 1) & 1, (k >> 2) & 1})]
                   : TVoxel::initial();
    }
}

// Observed corners must carry at least this share of the trilinear weight for an interpolated SDF to
// count (below it, `p` is as good as unobserved). 0.25 bridges the single unobserved voxels that depth
// holes leave; 0.5 does not, and a recording with a regular grid of depth holes then fails to track
// again. Larger shares keep silhouettes of surfaces seen from few views tighter.
constexpr float kMinObservedWeight = 0.25f;

// Trilinear interpolation of the SDF at `p` (grid units) over the observed corners, their weights
// renormalised: an unobserved voxel is unknown, not free space. (Counting it as +1 moved surfaces next
// to voxels that fell on depth holes, the empty rows and columns of registered depth, by a voxel and
// turned their normals by tens of degrees.) Returns +1 and `observed` = false when the observed corners
// carry less than kMinObservedWeight.
template <class TVoxel, class TIndexData>
VF_HOST_DEVICE inline float readSdfInterpolated(const TVoxel* voxels, const TIndexData& index, Vec3f p,
                                                bool& observed) {
    const Vec3i base = floorToInt(p);
    const Vec3f c = p - toFloat(base);
    TVoxel v[8];
    bool found[8];
    readCellVoxels(voxels, index, base, v, found);
    float result = 0.f, weight = 0.f;
    observed = false;
    for (int k = 0; k < 8; ++k) {
        const Vec3i o{k & 1, (k >> 1) & 1, (k >> 2) & 1};
        const float w = (o.x ? c.x : 1.f - c.x) * (o.y ? c.y : 1.f - c.y) * (o.z ? c.z : 1.f - c.z);
        const bool has_data = found[k] && v[k].w_depth > 0;
        if (!has_data) continue;
        result += w * TVoxel::sdfToFloat(v[k].sdf);
        weight += w;
    }
    observed = weight >= kMinObservedWeight;
    return observed ? result / weight : 1.f;
}

// A colour of readColorInterpolated as the RGBA pixel a render shows.
VF_HOST_DEVICE inline Vec4u8 renderColor(Vec3f rgb) {
    return {(unsigned char)clampValue(rgb.x, 0.f, 255.f), (unsigned char)clampValue(rgb.y, 0.f, 255.f),
            (unsigned char)clampValue(rgb.z, 0.f, 255.f), 255};
}

// Trilinear interpolation of colour (0..255 per channel) over the corners that have colour;
// `coloured` false (and black) where none has.
template <class TVoxel, class TIndexData>
VF_HOST_DEVICE inline Vec3f readColorInterpolated(const TVoxel* voxels, const TIndexData& index, Vec3f p,
                                                  bool& coloured) {
    const Vec3i base = floorToInt(p);
    const Vec3f c = p - toFloat(base);
    Vec3f sum{0.f, 0.f, 0.f};
    float weight_sum = 0.f;
    for (int k = 0; k < 8; ++k) {
        const Vec3i o{k & 1, (k >> 1) & 1, (k >> 2) & 1};
        bool found;
        const TVoxel v = readVoxel(voxels, index, base + o, found);
        if (!found || v.w_color == 0) continue;
        const float w = (o.x ? c.x : 1.f - c.x) * (o.y ? c.y : 1.f - c.y) * (o.z ? c.z : 1.f - c.z);
        sum += Vec3f{float(v.clr.x), float(v.clr.y), float(v.clr.z)} * w;
        weight_sum += w;
    }
    coloured = weight_sum > 0.f;
    return coloured ? sum / weight_sum : Vec3f{0.f, 0.f, 0.f};
}
template <class TVoxel, class TIndexData>
VF_HOST_DEVICE inline Vec3f readColorInterpolated(const TVoxel* voxels, const TIndexData& index, Vec3f p) {
    bool coloured;
    return readColorInterpolated(voxels, index, p, coloured);
}

// Class at `p` (grid units): the label of the nearest labelled corner of the cell around p, or
// kNoLabel when none of the eight is labelled. Class ids are never interpolated.
template <class TVoxel, class TIndexData>
VF_HOST_DEVICE inline ClassId readLabelNearest(const TVoxel* voxels, const TIndexData& index, Vec3f p) {
    const Vec3i base{int(floorf(p.x)), int(floorf(p.y)), int(floorf(p.z))};
    ClassId best = kNoLabel;
    float best_d2 = 1e30f;
    for (int k = 0; k < 8; ++k) {
        const Vec3i c = base + Vec3i{k & 1, (k >> 1) & 1, k >> 2};
        bool found;
        const TVoxel v = readVoxel(voxels, index, c, found);
        if (!found || v.w_label == 0) continue;
        const Vec3f d = toFloat(c) - p;
        const float d2 = dot(d, d);
        if (d2 < best_d2) {
            best_d2 = d2;
            best = v.label;
        }
    }
    return best;
}

// Outward surface normal (direction of increasing SDF) from central differences, one voxel apart.
template <class TVoxel, class TIndexData>
VF_HOST_DEVICE inline Vec3f sdfGradientNormal(const TVoxel* voxels, const TIndexData& index, Vec3f p) {
    bool o;
    Vec3f g;
    g.x = readSdfInterpolated(voxels, index, Vec3f{p.x + 1.f, p.y, p.z}, o) -
          readSdfInterpolated(voxels, index, Vec3f{p.x - 1.f, p.y, p.z}, o);
    g.y = readSdfInterpolated(voxels, index, Vec3f{p.x, p.y + 1.f, p.z}, o) -
          readSdfInterpolated(voxels, index, Vec3f{p.x, p.y - 1.f, p.z}, o);
    g.z = readSdfInterpolated(voxels, index, Vec3f{p.x, p.y, p.z + 1.f}, o) -
          readSdfInterpolated(voxels, index, Vec3f{p.x, p.y, p.z - 1.f}, o);
    return normalize(g);
}

}  // namespace voxfuse
