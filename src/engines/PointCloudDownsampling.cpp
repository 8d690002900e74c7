// Voxel-grid downsampling by centroid: bin, sort by cell, then average each run of equal cells.

#include "voxfuse/engines/PointCloudDownsampling.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "voxfuse/core/CpuThreads.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace {

struct BinnedPoint {
    Vec3i cell;
    std::uint32_t point;  // index in the input
};

bool cellBefore(const BinnedPoint& a, const BinnedPoint& b) {
    if (a.cell.z != b.cell.z) return a.cell.z < b.cell.z;
    if (a.cell.y != b.cell.y) return a.cell.y < b.cell.y;
    if (a.cell.x != b.cell.x) return a.cell.x < b.cell.x;
    return a.point < b.point;  // a total order: the sums below add in input order
}

// The most frequent class of the points [first, last), which it reorders; kNoLabel counts only when
// there is nothing else, and the smallest class wins a tie, so the points' order does not matter.
ClassId majorityLabel(BinnedPoint* first, BinnedPoint* last, const std::vector<ClassId>& labels) {
    auto label = [&labels](const BinnedPoint& b) { return labels[b.point]; };
    std::sort(first, last,
              [&label](const BinnedPoint& a, const BinnedPoint& b) { return label(a) < label(b); });  // kNoLabel last
    ClassId best = kNoLabel;
    std::ptrdiff_t best_count = 0;
    for (BinnedPoint *begin = first, *end = first; begin != last && label(*begin) != kNoLabel; begin = end) {
        while (end != last && label(*end) == label(*begin)) ++end;
        if (end - begin > best_count) {  // strictly more: of equal counts the first, smallest class stays
            best = label(*begin);
            best_count = end - begin;
        }
    }
    return best;
}

}  // namespace

PointCloud downsampleVoxelGrid(const PointCloud& cloud, float cell_m) {
    if (!(cell_m > 0.f) || !std::isfinite(cell_m))
        throw ConfigError("downsampling: the cell size must be a positive number (got " + std::to_string(cell_m) + ")");
    const std::size_t n = cloud.points.size();
    if (const std::string why = inconsistency(cloud); !why.empty())
        throw Error("downsampling: inconsistent cloud: " + why);
    if (n > std::size_t(UINT32_MAX)) throw Error("downsampling: more than 2^32 points");

    // Cell of every finite point.
    const double inv_cell = 1.0 / double(cell_m);
    std::vector<BinnedPoint> binned(n);
    std::vector<std::uint8_t> keep(n);
    std::atomic<bool> out_of_range{false};
    forEachCpuShare(n, 4096, [&](std::size_t begin, std::size_t end) {
        bool share_out_of_range = false;
        for (std::size_t i = begin; i < end; ++i) {
            const Vec3f p = cloud.points[i];
            keep[i] = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
            if (!keep[i]) continue;
            Vec3i cell{0, 0, 0};
            for (int a = 0; a < 3; ++a) {
                const double c = std::floor(double(p[a]) * inv_cell);
                share_out_of_range = share_out_of_range || c < double(INT32_MIN) || c > double(INT32_MAX);
                cell[a] = share_out_of_range ? 0 : int(c);
            }
            binned[i] = BinnedPoint{cell, std::uint32_t(i)};
        }
        if (share_out_of_range) out_of_range = true;
    });
    if (out_of_range)
        throw ConfigError("downsampling: cells of " + std::to_string(cell_m) +
                          " m are too small for the cloud's extent");
    std::size_t kept = 0;
    for (std::size_t i = 0; i < n; ++i)
        if (keep[i]) binned[kept++] = binned[i];
    binned.resize(kept);
    std::sort(binned.begin(), binned.end(), cellBefore);

    // Runs of equal cells; one output point per run.
    std::vector<std::size_t> run_starts;
    for (std::size_t i = 0; i < binned.size(); ++i)
        if (i == 0 || binned[i].cell != binned[i - 1].cell) run_starts.push_back(i);
    run_starts.push_back(binned.size());
    const std::size_t runs = run_starts.size() - 1;

    PointCloud out;
    out.points.resize(runs);
    if (cloud.hasNormals()) out.normals.resize(runs);
    if (cloud.hasColors()) out.colors.resize(runs);
    if (cloud.hasLabels()) out.labels.resize(runs);
    forEachCpuShare(runs, 256, [&](std::size_t first_run, std::size_t end_run) {
        for (std::size_t r = first_run; r < end_run; ++r) {
            const std::size_t begin = run_starts[r], end = run_starts[r + 1];
            double sum_p[3] = {0, 0, 0}, sum_n[3] = {0, 0, 0}, sum_c[3] = {0, 0, 0};
            for (std::size_t k = begin; k < end; ++k) {
                const std::size_t i = binned[k].point;
                for (int a = 0; a < 3; ++a) {
                    sum_p[a] += cloud.points[i][a];
                    if (cloud.hasNormals()) sum_n[a] += cloud.normals[i][a];
                    if (cloud.hasColors()) sum_c[a] += cloud.colors[i][a];
                }
            }
            const double count = double(end - begin);
            out.points[r] = Vec3f{float(sum_p[0] / count), float(sum_p[1] / count), float(sum_p[2] / count)};
            if (cloud.hasNormals())
                out.normals[r] = normalize(Vec3f{float(sum_n[0]), float(sum_n[1]), float(sum_n[2])});
            if (cloud.hasColors())
                out.colors[r] =
                    Vec3u8{std::uint8_t(std::lround(sum_c[0] / count)), std::uint8_t(std::lround(sum_c[1] / count)),
                           std::uint8_t(std::lround(sum_c[2] / count))};
            // Last: it reorders the run (the sums above needed input order).
            if (cloud.hasLabels())
                out.labels[r] = majorityLabel(binned.data() + begin, binned.data() + end, cloud.labels);
        }
    });
    return out;
}

}  // namespace voxfuse
