#pragma once
// The CPU's own loop shapes of low-level image operations (engines/LowLevelEngine_Impl.h picks them
// when the device is not kOneThreadPerItem): wide elements, a strip or a row of cells each, whose inner
// loops the compiler vectorises. The per-element bodies both devices share are in shared/LowLevel.h.
//
// Contract: each shape gives bit for bit the output of the shared body it stands for, for every image;
// tests/engines/GpuShapesOnCpuTest.cpp (GpuShapesOnCpuLowLevelTest) holds them to it.

#include "voxfuse/shared/LowLevel.h"

namespace voxfuse {

// The CPU's launch shape of the same filter: element e is a strip of up to kBilateralStripWidth
// columns and kBilateralStripRows rows, taken row by row and tap by tap across the row (loops the
// compiler vectorises). A tap's weight is symmetric, w(p, q) = w(q, p) (the same squared difference and
// spatial factor), so each pair of pixels is weighed once: row y computes the pairs it makes with the
// taps ahead of it (later rows, or later in its row) into a ring of the last radius + 1 rows, and a
// pixel's taps behind it read the pair its tap's row computed. Every pixel still adds the same terms in
// the same order as bilateralFilterDepthPixel (a skipped tap adds +0): the images are bit-identical
// (for finite depths). The exponential was most of a tap's cost; now half the taps pay it.
constexpr int kBilateralStripWidth = 128;
constexpr int kBilateralStripRows = 32;
constexpr int kBilateralPairBuffer = 16384;  // floats of pair weights per element (on its stack)
struct BilateralFilterStrips {
    const float* in;
    Vec2i size;
    BilateralWeights weights;
    float* out;

    // Taps ahead of a pixel: (0, 1..r), then (1..r, -r..r).
    int aheadCount() const { return weights.radius_px * (2 * weights.radius_px + 2); }
    int aheadIndex(int dy, int dx) const {
        return dy == 0 ? dx - 1 : weights.radius_px + (dy - 1) * (2 * weights.radius_px + 1) + dx + weights.radius_px;
    }
    // Columns per strip: as many as the ring of pair weights holds (a large radius gets narrow strips).
    int stripWidth() const {
        const int r = weights.radius_px;
        if (r == 0) return kBilateralStripWidth;
        const int fit = kBilateralPairBuffer / (aheadCount() * (r + 1)) - 2 * r;
        return fit < kBilateralStripWidth ? (fit > 1 ? fit : 1) : kBilateralStripWidth;
    }
    int stripsPerRow() const { return (size.x + stripWidth() - 1) / stripWidth(); }
    int elementCount() const { return stripsPerRow() * ((size.y + kBilateralStripRows - 1) / kBilateralStripRows); }

    void operator()(int e) const {
        const int r = weights.radius_px, width = stripWidth(), ahead = aheadCount();
        const int x0 = (e % stripsPerRow()) * width, row0 = (e / stripsPerRow()) * kBilateralStripRows;
        const int n = size.x - x0 < width ? size.x - x0 : width;
        const int row1 = size.y - row0 < kBilateralStripRows ? size.y : row0 + kBilateralStripRows;
        const int columns = n + 2 * r;      // the ring's columns: x0 - r .. x0 + n + r - 1
        float pairs[kBilateralPairBuffer];  // [row % (r + 1)][ahead tap][column]
        auto pairRow = [&](int y, int tap) { return pairs + ((y % (r + 1)) * ahead + tap) * columns; };
        // Row y's pairs with its taps ahead, for the columns whose pair lies inside the image.
        auto weighPairs = [&](int y) {
            for (int dy = 0; dy <= r && y + dy < size.y; ++dy)
                for (int dx = dy == 0 ? 1 : -r; dx <= r; ++dx) {
                    const float w_tap = weights.spatial[dy] * weights.spatial[dx > 0 ? dx : -dx];
                    int c0 = x0 - r > 0 ? x0 - r : 0, c1 = x0 + n + r < size.x ? x0 + n + r : size.x;
                    c0 = c0 > -dx ? c0 : -dx;
                    c1 = c1 < size.x - dx ? c1 : size.x - dx;
                    float* w = pairRow(y, aheadIndex(dy, dx));  // column c at w[c - (x0 - r)]
                    const float* here = in + y * size.x;
                    const float* there = in + (y + dy) * size.x;
                    for (int c = c0; c < c1; ++c) {
                        const float diff = there[c + dx] - here[c];
                        w[c - (x0 - r)] = w_tap * expOfNegative(diff * diff * weights.inv_2_sigma_depth_sq);
                    }
                }
        };
        for (int y = row0 - r > 0 ? row0 - r : 0; y < row0; ++y) weighPairs(y);
        const float centre_weight = weights.spatial[0] * weights.spatial[0] * expOfNegative(0.f);
        float sum[kBilateralStripWidth], weight_sum[kBilateralStripWidth];
        for (int y = row0; y < row1; ++y) {
            weighPairs(y);
            const float* centre = in + y * size.x + x0;
            for (int i = 0; i < n; ++i) sum[i] = weight_sum[i] = 0.f;
            const int y0 = y - r > 0 ? y - r : 0, y1 = y + r < size.y - 1 ? y + r : size.y - 1;
            for (int yy = y0; yy <= y1; ++yy)
                for (int dx = -r; dx <= r; ++dx) {
                    const int dy = yy - y;
                    // The tap's pair weight: ahead, in this row's pairs; behind, in the tap's row's pairs
                    // (its pair ahead by (-dy, -dx)); the centre, its own.
                    const bool is_ahead = dy > 0 || (dy == 0 && dx > 0);
                    const float* w = dy == 0 && dx == 0 ? nullptr
                                     : is_ahead         ? pairRow(y, aheadIndex(dy, dx)) + r
                                                        : pairRow(yy, aheadIndex(-dy, -dx)) + r + dx;
                    const float* tap = in + yy * size.x + x0 + dx;
                    const int i0 = x0 + dx < 0 ? -(x0 + dx) : 0;
                    const int i1 = size.x - (x0 + dx) < n ? size.x - (x0 + dx) : n;
                    if (w == nullptr) {
                        for (int i = i0; i < i1; ++i) {
                            const float d = tap[i];
                            const bool valid = d > 0.f;
                            sum[i] += valid ? centre_weight * d : 0.f;
                            weight_sum[i] += valid ? centre_weight : 0.f;
                        }
                        continue;
                    }
                    for (int i = i0; i < i1; ++i) {
                        const float d = tap[i];
                        const bool valid = d > 0.f;
                        sum[i] += valid ? w[i] * d : 0.f;
                        weight_sum[i] += valid ? w[i] : 0.f;
                    }
                }
            float* out_row = out + y * size.x + x0;
            for (int i = 0; i < n; ++i) out_row[i] = centre[i] > 0.f ? sum[i] / weight_sum[i] : 0.f;
        }
    }
};

// The CPU's shape: element r is cell row r, its columns' sums taken row by row across up to
// kCellColumnChunk columns at a time (loops the compiler vectorises), then each cell's across them.
constexpr int kCellColumnChunk = 256;
template <class Sample>
struct CellRowAverages {
    Sample sample;
    Vec2i frame, cells;
    Vec2f* mean_and_count;
    void operator()(int cy) const {
        const int y_begin = firstPixelOfCell(cy, cells.y, frame.y), y_end = firstPixelOfCell(cy + 1, cells.y, frame.y);
        float column_sum[kCellColumnChunk], column_count[kCellColumnChunk];
        int cx = 0;
        while (cx < cells.x) {
            // As many whole cells as the chunk holds (at least one; a wider cell goes column by column).
            const int x0 = firstPixelOfCell(cx, cells.x, frame.x);
            int cx_end = cx + 1;
            while (cx_end < cells.x && firstPixelOfCell(cx_end + 1, cells.x, frame.x) - x0 <= kCellColumnChunk)
                ++cx_end;
            const int x1 = firstPixelOfCell(cx_end, cells.x, frame.x);
            if (x1 - x0 > kCellColumnChunk) {
                CellAverages<Sample>{sample, frame, cells, mean_and_count}(cx + cy * cells.x);
                cx = cx_end;
                continue;
            }
            for (int x = 0; x < x1 - x0; ++x) column_sum[x] = column_count[x] = 0.f;
            for (int y = y_begin; y < y_end; ++y)
                for (int x = x0; x < x1; ++x) {
                    float value;
                    const bool ok = sample(x + y * frame.x, value);
                    column_sum[x - x0] += ok ? value : 0.f;
                    column_count[x - x0] += ok ? 1.f : 0.f;
                }
            for (; cx < cx_end; ++cx) {
                float sum = 0.f, count = 0.f;
                for (int x = firstPixelOfCell(cx, cells.x, frame.x); x < firstPixelOfCell(cx + 1, cells.x, frame.x);
                     ++x) {
                    sum += column_sum[x - x0];
                    count += column_count[x - x0];
                }
                mean_and_count[cx + cy * cells.x] = Vec2f{count > 0.f ? sum / count : 0.f, count};
            }
        }
    }
};

}  // namespace voxfuse
