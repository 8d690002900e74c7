#include "MapOutputBench.h"

#include <algorithm>
#include <cstdio>
#include <utility>
#include <vector>

#include "ResourceUsage.h"
#include "Statistics.h"
#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/Timer.h"
#include "voxfuse/engines/PointCloudDownsampling.h"

namespace voxfuse::app {

MeshingBench benchMeshing(MainEngine& engine, int repeats, Mesh* first_mesh) {
    MeshingBench b;
    b.repeats = std::max(1, repeats);
    std::vector<double> ms;
    for (int r = 0; r < b.repeats; ++r) {
        Mesh mesh;
        // Only the first run starts from nothing: later ones could reuse pages the allocator kept.
        const StagePeakMemory peak;
        const std::size_t gpu_before = device_memory::bytesInUse();
        device_memory::resetPeakBytes();
        const Timer t;
        engine.extractMesh(mesh);
        ms.push_back(t.elapsedMs());
        if (r == 0) {
            b.peak_extra_mb = peak.extraMb();
            if (engine.settings().device == Device::CUDA)
                b.gpu_peak_extra_mb = double(device_memory::peakBytesInUse() - gpu_before) / (1024.0 * 1024.0);
            b.vertices = (long long)mesh.vertices.size();
            b.triangles = (long long)mesh.triangles.size();
            b.mesh_mb = double(mesh.bytes()) / (1024.0 * 1024.0);
            if (first_mesh) *first_mesh = std::move(mesh);
        }
    }
    b.median_ms = median(ms);
    b.min_ms = *std::min_element(ms.begin(), ms.end());
    return b;
}

CloudBench benchCloud(MainEngine& engine, int repeats, float cell_m) {
    CloudBench b;
    b.repeats = std::max(1, repeats);
    b.cell_m = cell_m;
    std::vector<double> extract_ms, downsample_ms;
    for (int r = 0; r < b.repeats; ++r) {
        PointCloud cloud;
        Timer t;
        engine.extractPointCloud(cloud);
        extract_ms.push_back(t.elapsedMs());
        b.points = (long long)cloud.size();
        if (cell_m <= 0.f) continue;
        t = Timer();
        const PointCloud down = downsampleVoxelGrid(cloud, cell_m);
        downsample_ms.push_back(t.elapsedMs());
        b.downsampled_points = (long long)down.size();
    }
    b.extract_median_ms = median(extract_ms);
    b.downsample_median_ms = median(downsample_ms);
    return b;
}

void printMeshing(const MeshingBench& b) {
    std::printf(
        "\n  meshing (marching cubes, median of %d): %.1f ms (min %.1f), %lld vertices, %lld triangles, mesh %.1f MB",
        b.repeats, b.median_ms, b.min_ms, b.vertices, b.triangles, b.mesh_mb);
    if (b.peak_extra_mb >= 0.0)
        std::printf(", peak +%.1f MB (%.2f x the mesh)", b.peak_extra_mb,
                    b.mesh_mb > 0.0 ? b.peak_extra_mb / b.mesh_mb : 0.0);
    if (b.gpu_peak_extra_mb >= 0.0)
        std::printf(", GPU peak +%.1f MB (%.2f x the mesh)", b.gpu_peak_extra_mb,
                    b.mesh_mb > 0.0 ? b.gpu_peak_extra_mb / b.mesh_mb : 0.0);
    std::printf("\n");
}

void printCloud(const CloudBench& b) {
    std::printf("  point cloud (median of %d): %.1f ms, %lld points", b.repeats, b.extract_median_ms, b.points);
    if (b.cell_m > 0.f)
        std::printf("; downsampled to %.1f mm cells in %.1f ms, %lld points", 1000.0 * b.cell_m, b.downsample_median_ms,
                    b.downsampled_points);
    std::printf("\n");
}

namespace {

double perFrameMs(const OccupancyStats& s) {
    return s.frames_inserted > 0 ? s.insert_ms / double(s.frames_inserted) : 0.0;
}

}  // namespace

void printOccupancy(const OccupancyStats& s, const OccupancySettings& settings) {
    const double ms = perFrameMs(s);
    std::printf(
        "  occupancy (%.0f mm cells, every %d%s pixel, every %d%s frame): %lld of %lld frames inserted, %lld dropped; "
        "worker %.1f ms per frame = %.1f frames/s, %.2f M points/s\n",
        1000.0 * settings.resolution_m, settings.pixel_step, settings.pixel_step == 1 ? "st" : "th",
        settings.frame_step, settings.frame_step == 1 ? "st" : "th", (long long)s.frames_inserted,
        (long long)s.frames_submitted, (long long)s.frames_dropped, ms, ms > 0.0 ? 1000.0 / ms : 0.0,
        s.insert_ms > 0.0 ? double(s.points_inserted) / s.insert_ms / 1000.0 : 0.0);
}

Json meshingJson(const MeshingBench& b) {
    Json j;
    j["repeats"] = b.repeats;
    j["median_ms"] = b.median_ms;
    j["min_ms"] = b.min_ms;
    j["vertices"] = b.vertices;
    j["triangles"] = b.triangles;
    j["mesh_mb"] = b.mesh_mb;
    if (b.peak_extra_mb >= 0.0) j["peak_extra_mb"] = b.peak_extra_mb;
    if (b.gpu_peak_extra_mb >= 0.0) j["gpu_peak_extra_mb"] = b.gpu_peak_extra_mb;
    return j;
}

Json cloudJson(const CloudBench& b) {
    Json j;
    j["repeats"] = b.repeats;
    j["extract_median_ms"] = b.extract_median_ms;
    j["points"] = b.points;
    if (b.cell_m > 0.f) {
        j["cell_m"] = double(b.cell_m);
        j["downsample_median_ms"] = b.downsample_median_ms;
        j["downsampled_points"] = b.downsampled_points;
    }
    return j;
}

Json occupancyJson(const OccupancyStats& s, const OccupancySettings& settings) {
    const double ms = perFrameMs(s);
    Json j;
    j["resolution_m"] = double(settings.resolution_m);
    j["pixel_step"] = settings.pixel_step;
    j["frame_step"] = settings.frame_step;
    j["frames_submitted"] = (long long)s.frames_submitted;
    j["frames_inserted"] = (long long)s.frames_inserted;
    j["frames_dropped"] = (long long)s.frames_dropped;
    j["points_inserted"] = (long long)s.points_inserted;
    j["worker_ms_per_frame"] = ms;
    j["worker_fps"] = ms > 0.0 ? 1000.0 / ms : 0.0;
    return j;
}

}  // namespace voxfuse::app
