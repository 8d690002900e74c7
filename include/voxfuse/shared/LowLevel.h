#pragma once
// Per-pixel image operations before tracking and integration: depth conversion, bilateral filter,
// pyramid downsampling, vertex and normal maps.

#include <cstdint>

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/Intrinsics.h"
#include "voxfuse/objects/RGBDCalib.h"

namespace voxfuse {

// The bilateral filter's window reaches at most this many pixels from its centre.
constexpr int kMaxBilateralRadius = 7;

// What every pixel of one bilateral filter pass shares: the spatial weight is separable, so one
// factor per pixel offset, e^(-k^2 / 2 sigma_space^2), made once per pass.
struct BilateralWeights {
    int radius_px;                           // <= kMaxBilateralRadius
    float spatial[kMaxBilateralRadius + 1];  // by |dx| and |dy|
    float inv_2_sigma_depth_sq;              // 1 / (2 sigma_depth^2), 1/m^2
};

// Edge-preserving smoothing of one depth pixel (KinectFusion's bilateral filter). Invalid (0) pixels
// stay invalid and never contribute.
VF_HOST_DEVICE inline float bilateralFilterDepthPixel(const float* depth, Vec2i size, int x, int y,
                                                      const BilateralWeights& w) {
    const float centre = depth[x + y * size.x];
    if (!(centre > 0.f)) return 0.f;
    const int r = w.radius_px;
    const int y0 = y - r > 0 ? y - r : 0, y1 = y + r < size.y - 1 ? y + r : size.y - 1;
    const int x0 = x - r > 0 ? x - r : 0, x1 = x + r < size.x - 1 ? x + r : size.x - 1;
    float sum = 0.f, weight_sum = 0.f;
    for (int yy = y0; yy <= y1; ++yy) {
        const float wy = w.spatial[yy > y ? yy - y : y - yy];
        const float* row = depth + yy * size.x;
        for (int xx = x0; xx <= x1; ++xx) {
            const float d = row[xx];
            if (!(d > 0.f)) continue;
            const float diff = d - centre;
            const float weight =
                wy * w.spatial[xx > x ? xx - x : x - xx] * expOfNegative(diff * diff * w.inv_2_sigma_depth_sq);
            sum += weight * d;
            weight_sum += weight;
        }
    }
    return sum / weight_sum;  // weight_sum >= 1 (the centre itself)
}

// One pixel of the next pyramid level: the mean of the valid samples of the 2x2 block that lie within
// `max_diff_m` of the block's first valid sample (averaging across depth edges would invent surfaces).
VF_HOST_DEVICE inline float downsampleDepthPixel(const float* depth, Vec2i size, int x, int y, float max_diff_m) {
    float ref = 0.f, sum = 0.f;
    int n = 0;
    for (int k = 0; k < 4; ++k) {
        const int xx = 2 * x + (k & 1), yy = 2 * y + (k >> 1);
        if (xx >= size.x || yy >= size.y) continue;
        const float d = depth[xx + yy * size.x];
        if (!(d > 0.f)) continue;
        if (n == 0) ref = d;
        if (fabsf(d - ref) > max_diff_m) continue;
        sum += d;
        ++n;
    }
    return n > 0 ? sum / float(n) : 0.f;
}

// Camera-frame point of a depth pixel; w = 1 when valid, 0 otherwise.
VF_HOST_DEVICE inline Vec4f vertexFromDepthPixel(const float* depth, const Intrinsics& intr, int x, int y) {
    const float d = depth[x + y * intr.width];
    if (!(d > 0.f)) return {0.f, 0.f, 0.f, 0.f};
    const Vec3f p = intr.unproject(float(x), float(y), d);
    return {p.x, p.y, p.z, 1.f};
}

// Camera-frame points of a depth image, unprojected where read: the vertex map's values without
// holding it (normals of a subsampled level read 5-9 pixels around each of a quarter of the pixels).
struct DepthImagePoints {
    const float* depth;
    Intrinsics intrinsics;
    VF_HOST_DEVICE Vec4f operator()(int x, int y) const { return vertexFromDepthPixel(depth, intrinsics, x, y); }
};
// The points of a vertex map (or any image of points, w > 0 where valid).
struct VertexImagePoints {
    const Vec4f* vertices;
    int width;
    VF_HOST_DEVICE Vec4f operator()(int x, int y) const { return vertices[x + y * width]; }
};

// One side of a normal's difference: the nearest valid vertex within 2 pixels along (sx, sy). Missing
// samples (holes: dropouts, the empty rows and columns of depth registered to another camera) are
// stepped over; a sample more than `max_step_m` per pixel away from the centre is a depth edge, and then
// the side has no neighbour (the edge is not bridged by looking further). Returns the pixel distance
// (1 or 2), or 0 when the side has no usable neighbour. `points(x, y)` is pixel (x, y)'s point.
template <class Points>
VF_HOST_DEVICE inline int normalNeighbour(const Points& points, Vec2i size, int x, int y, int sx, int sy, Vec3f centre,
                                          float max_step_m, Vec3f& out) {
    for (int k = 1; k <= 2; ++k) {
        const int xx = x + k * sx, yy = y + k * sy;
        if (xx < 0 || yy < 0 || xx >= size.x || yy >= size.y) return 0;
        const Vec4f p = points(xx, yy);
        if (p.w <= 0.f) continue;                                        // a hole: look one pixel further
        if (length(p.xyz() - centre) > max_step_m * float(k)) return 0;  // a depth edge
        out = p.xyz();
        return k;
    }
    return 0;
}

// Normal of a valid vertex from differences of the vertex map, oriented towards the camera at `camera`
// (the origin for camera-frame vertices; the camera centre for world points); w = 0 when
// the vertex is invalid, or an axis has no usable neighbour on either side. Per axis: the central
// difference when both sides have a neighbour within 2 pixels, else the one-sided difference, so that
// isolated missing pixels and one-pixel hole lines do not take the normals of their neighbours with
// them. `max_edge_m` bounds a two-pixel difference (half of it per pixel): larger steps are depth edges.
template <class Points>
VF_HOST_DEVICE inline Vec4f normalAtPixel(const Points& points, Vec2i size, int x, int y, float max_edge_m,
                                          Vec3f camera = Vec3f{0.f, 0.f, 0.f}) {
    const Vec4f invalid{0.f, 0.f, 0.f, 0.f};
    const Vec4f centre = points(x, y);
    if (centre.w <= 0.f) return invalid;
    const Vec3f c = centre.xyz();
    const float max_step_m = 0.5f * max_edge_m;
    Vec3f l = c, r = c, u = c, d = c;
    const int kl = normalNeighbour(points, size, x, y, -1, 0, c, max_step_m, l);
    const int kr = normalNeighbour(points, size, x, y, 1, 0, c, max_step_m, r);
    const int ku = normalNeighbour(points, size, x, y, 0, -1, c, max_step_m, u);
    const int kd = normalNeighbour(points, size, x, y, 0, 1, c, max_step_m, d);
    if ((kl == 0 && kr == 0) || (ku == 0 && kd == 0)) return invalid;
    const Vec3f dx = r - l, dy = d - u;  // a missing side stays at the centre: a one-sided difference
    Vec3f n = normalize(cross(dy, dx));
    if (dot(n, c - camera) > 0.f) n = -n;  // face the camera
    return {n.x, n.y, n.z, 1.f};
}
VF_HOST_DEVICE inline Vec4f normalFromVertexPixel(const Vec4f* vertices, Vec2i size, int x, int y, float max_edge_m,
                                                  Vec3f camera = Vec3f{0.f, 0.f, 0.f}) {
    return normalAtPixel(VertexImagePoints{vertices, size.x}, size, x, y, max_edge_m, camera);
}

// Every `step`-th pixel of an image of width `width` along both axes, starting at pixel (0, 0):
// element i of the grid is pixel index(i) of the image.
struct PixelGrid {
    int width;       // of the image
    int step;        // 1: every pixel
    int grid_width;  // (width + step - 1) / step
    VF_HOST_DEVICE int index(int i) const { return (i % grid_width) * step + (i / grid_width) * step * width; }
};
// The grid of an image of `image_size`: its columns and rows, the grid itself, its number of elements.
inline Vec2i gridExtent(Vec2i image_size, int step) {
    return {(image_size.x + step - 1) / step, (image_size.y + step - 1) / step};
}
inline PixelGrid pixelGridOf(Vec2i image_size, int step) {
    return {image_size.x, step, gridExtent(image_size, step).x};
}
inline int gridSize(Vec2i image_size, int step) {
    const Vec2i extent = gridExtent(image_size, step);
    return extent.x * extent.y;
}

// ---- Loop bodies of the device layers: element i is pixel i of the output image ----

// Raw depth to metres. A sample outside [min_m, max_m] becomes 0. A pixel the sensor left empty
// (raw 0, or no valid disparity) between two kept neighbours on one line, left and right or else
// above and below, whose depths differ by at most gap_tolerance times the nearer one, takes their
// mean (0 turns this off). Sensors that drop single pixels, rows or columns would otherwise leave
// the same grid of unobserved voxels in the map frame after frame, which the tracker then meets as
// holes in the model. Across a depth edge the neighbours disagree, so nothing is invented there.
struct ConvertDepthPixels {
    const std::uint16_t* raw;
    Vec2i size;
    DisparityCalib calib;
    float fx_depth, min_m, max_m;
    float gap_tolerance;
    float* depth_m;

    VF_HOST_DEVICE float kept(int i) const {
        const float d = calib.toMetres(raw[i], fx_depth);
        return (d >= min_m && d <= max_m) ? d : 0.f;
    }
    VF_HOST_DEVICE bool bridge(int a, int b, float& out) const {
        if (raw[a] == 0 || raw[b] == 0) return false;  // most gaps lie in larger holes: no conversion there
        const float da = kept(a), db = kept(b);
        if (!(da > 0.f) || !(db > 0.f)) return false;
        const float nearer = da < db ? da : db;
        if (fabsf(da - db) > gap_tolerance * nearer) return false;
        out = 0.5f * (da + db);
        return true;
    }
    VF_HOST_DEVICE void operator()(int i) const {
        const float d = calib.toMetres(raw[i], fx_depth);
        if (d > 0.f || !(gap_tolerance > 0.f)) {
            depth_m[i] = (d >= min_m && d <= max_m) ? d : 0.f;
            return;
        }
        const int x = i % size.x, y = i / size.x;
        float filled = 0.f;
        if (!(x > 0 && x + 1 < size.x && bridge(i - 1, i + 1, filled)) && y > 0 && y + 1 < size.y)
            bridge(i - size.x, i + size.x, filled);
        depth_m[i] = filled;
    }
};

struct BilateralFilterPixels {
    const float* in;
    Vec2i size;
    BilateralWeights weights;
    float* out;
    VF_HOST_DEVICE void operator()(int i) const {
        out[i] = bilateralFilterDepthPixel(in, size, i % size.x, i / size.x, weights);
    }
};

struct DownsampleDepthPixels {
    const float* in;
    Vec2i in_size;
    int out_width;
    float max_diff_m;
    float* out;
    VF_HOST_DEVICE void operator()(int i) const {
        out[i] = downsampleDepthPixel(in, in_size, i % out_width, i / out_width, max_diff_m);
    }
};

struct VertexPixels {
    const float* depth;
    Intrinsics intrinsics;
    Vec4f* vertices;
    VF_HOST_DEVICE void operator()(int i) const {
        vertices[i] = vertexFromDepthPixel(depth, intrinsics, i % intrinsics.width, i / intrinsics.width);
    }
};

struct NormalPixels {
    const Vec4f* vertices;
    Vec2i size;
    float max_edge_m;
    Vec4f* normals;
    VF_HOST_DEVICE void operator()(int i) const {
        normals[i] = normalFromVertexPixel(vertices, size, i % size.x, i / size.x, max_edge_m);
    }
};

// Element i is grid element i of a depth image: its camera-frame point and normal (as VertexPixels and
// NormalPixels make them at that pixel), packed into images of the grid's size.
struct GridPointNormalPixels {
    DepthImagePoints points;
    Vec2i size;
    float max_edge_m;
    PixelGrid grid;
    Vec4f* vertices;
    Vec4f* normals;
    VF_HOST_DEVICE void operator()(int i) const {
        const int p = grid.index(i);
        const int x = p % size.x, y = p / size.x;
        vertices[i] = points(x, y);
        normals[i] = normalAtPixel(points, size, x, y, max_edge_m);
    }
};

template <class T>
struct CopyPixels {
    const T* in;
    T* out;
    VF_HOST_DEVICE void operator()(int i) const { out[i] = in[i]; }
};

// Depths beyond max_depth_m become 0 (no measurement, as elsewhere), in place.
struct DropDepthBeyond {
    float* depth;
    float max_depth_m;
    VF_HOST_DEVICE void operator()(int i) const {
        if (!(depth[i] <= max_depth_m)) depth[i] = 0.f;
    }
};

// Block averages of a frame, for the relocaliser's fern codes (engines/FernEncoder.h): cell (cx, cy) of
// a cells.x x cells.y grid laid over the frame holds its pixels [cx * W / w, (cx + 1) * W / w) x
// [cy * H / h, (cy + 1) * H / h) (bounds rounded up); its output is the mean of the cell's valid
// samples and how many there were ({0, 0} for none). Every cell's sums run down each of its columns,
// then across the columns in order, so both launch shapes below, and both devices, give the same bits.
VF_HOST_DEVICE inline int firstPixelOfCell(int cell, int cells, int frame_pixels) {
    return int((static_cast<long long>(cell) * frame_pixels + cells - 1) / cells);
}

// Depth in metres over the pixels that have one (> 0); intensity (r + g + b, 0..765) over every pixel.
struct DepthSample {
    const float* depth_m;
    VF_HOST_DEVICE bool operator()(int pixel, float& value) const {
        value = depth_m[pixel];
        return value > 0.f;
    }
};
struct IntensitySample {
    const Vec4u8* rgb;
    VF_HOST_DEVICE bool operator()(int pixel, float& value) const {
        const Vec4u8 p = rgb[pixel];
        value = float(p.x) + float(p.y) + float(p.z);
        return true;
    }
};

// The GPU's shape: element c is cell c (row-major), a thread per cell.
template <class Sample>
struct CellAverages {
    Sample sample;
    Vec2i frame, cells;
    Vec2f* mean_and_count;
    VF_HOST_DEVICE void operator()(int c) const {
        const int cx = c % cells.x, cy = c / cells.x;
        const int y_begin = firstPixelOfCell(cy, cells.y, frame.y), y_end = firstPixelOfCell(cy + 1, cells.y, frame.y);
        float sum = 0.f, count = 0.f;
        for (int x = firstPixelOfCell(cx, cells.x, frame.x); x < firstPixelOfCell(cx + 1, cells.x, frame.x); ++x) {
            float column_sum = 0.f, column_count = 0.f;
            for (int y = y_begin; y < y_end; ++y) {
                float value;
                const bool ok = sample(x + y * frame.x, value);
                column_sum += ok ? value : 0.f;
                column_count += ok ? 1.f : 0.f;
            }
            sum += column_sum;
            count += column_count;
        }
        mean_and_count[c] = Vec2f{count > 0.f ? sum / count : 0.f, count};
    }
};

// Selections for the launchers' countIf.
struct DepthIsValid {
    const float* depth;
    PixelGrid grid;
    VF_HOST_DEVICE bool operator()(int i) const { return depth[grid.index(i)] > 0.f; }
};
struct PointIsValid {
    const Vec4f* points;
    VF_HOST_DEVICE bool operator()(int i) const { return points[i].w > 0.f; }
};

}  // namespace voxfuse
