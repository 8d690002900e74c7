#pragma once
// The map outputs of voxfuse_bench: what taking a mesh, a point cloud or an occupancy map out of a
// fused scene costs (time, size, the extra memory at its peak), measured after or beside the run.

#include <string>

#include "JsonFile.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/mapping/OccupancyMapper.h"

namespace voxfuse::app {

struct MeshingBench {
    int repeats = 0;
    double median_ms = 0.0, min_ms = 0.0;
    long long vertices = 0, triangles = 0;
    double mesh_mb = 0.0;             // the arrays of the finished mesh
    double peak_extra_mb = -1.0;      // resident memory above the pre-meshing level at the peak (< 0: unknown)
    double gpu_peak_extra_mb = -1.0;  // GPU memory above the pre-meshing level at the peak (< 0: a CPU run)
};

struct CloudBench {
    int repeats = 0;
    double extract_median_ms = 0.0;
    long long points = 0;
    float cell_m = 0.f;  // > 0: also downsampled to one point per cell
    double downsample_median_ms = 0.0;
    long long downsampled_points = 0;
};

// Extracts the engine's mesh `repeats` times (the first also measures the peak memory, and its mesh
// goes to `first_mesh` when given, for a caller that also writes it out).
MeshingBench benchMeshing(MainEngine& engine, int repeats, Mesh* first_mesh = nullptr);
// Extracts the point cloud, and downsamples it when cell_m > 0, `repeats` times.
CloudBench benchCloud(MainEngine& engine, int repeats, float cell_m);

void printMeshing(const MeshingBench& b);
void printCloud(const CloudBench& b);
// After OccupancyMapper::finish(): frames inserted and dropped, and the worker's own throughput.
void printOccupancy(const OccupancyStats& s, const OccupancySettings& settings);

// The "meshing", "point_cloud" and "occupancy" objects of voxfuse_bench.json.
Json meshingJson(const MeshingBench& b);
Json cloudJson(const CloudBench& b);
Json occupancyJson(const OccupancyStats& s, const OccupancySettings& settings);

}  // namespace voxfuse::app
