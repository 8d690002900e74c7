// voxfuse_bench: per-stage timings of the pipeline on a recorded sequence, as a table and as JSON, and
// on request what the map outputs cost (meshing, point clouds, the occupancy map's thread).
// Defaults to TUM fr3/teddy from ../shared/data when present, else the bundled synthetic sequence.
// `synthetic[:N]` renders the synthetic room in memory instead (no image files, no codec); a depth pack
// (DepthPackSource.h) is a recording without codecs. These two are the sources of a build without I/O
// (VOXFUSE_IO=OFF), such as the GPU bundle of scripts/gpu_bundle.sh.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>

#include "DepthPackSource.h"
#include "Interrupt.h"
#include "JsonFile.h"
#include "MapOutputBench.h"
#include "EngineOptions.h"
#include "OptionChecks.h"
#include "HeapPolicy.h"
#include "CommandLine.h"
#include "DefaultData.h"
#include "ProgramMain.h"
#include "ResourceUsage.h"
#include "RunRecord.h"
#include "SequenceRunner.h"
#include "Statistics.h"
#include "SyntheticSource.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/core/Timer.h"
#include "voxfuse/io/AtomicFile.h"
#include "voxfuse/io/MeshIO.h"
#include "voxfuse/io/TrajectoryIO.h"
#if VOXFUSE_WITH_IO
#include "LabelInput.h"
#include "voxfuse/io/UndistortedImageSource.h"
#endif

namespace fs = std::filesystem;
using namespace voxfuse;

namespace {

struct StageSummary {
    double median_ms = 0, mean_ms = 0, p90_ms = 0;
};

double meanOf(const std::vector<double>& v) {
    double sum = 0;
    for (const double x : v) sum += x;
    return v.empty() ? 0.0 : sum / double(v.size());
}

StageSummary summarise(std::vector<double> v) {
    StageSummary s;
    if (v.empty()) return s;
    s.median_ms = app::median(v);
    s.mean_ms = meanOf(v);
    std::sort(v.begin(), v.end());
    s.p90_ms = v[std::min(v.size() - 1, std::size_t(0.9 * double(v.size())))];
    return s;
}

std::string formatMillimetres(double metres) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.2f", 1000.0 * metres);
    return text;
}

std::string defaultSource() {
#if VOXFUSE_WITH_IO
    const std::string teddy = std::string(VOXFUSE_SHARED_DATA_DIR) + "/tum_fr3_teddy_200";
    if (fs::exists(teddy + "/rgb.txt")) return teddy;
    return app::bundledSequence("voxfuse_bench");
#else
    return "synthetic";
#endif
}

std::unique_ptr<ImageSource> openSource(const std::string& path) {
    if (app::SyntheticSource::isSyntheticName(path)) return app::SyntheticSource::open(path);
    if (app::DepthPackSource::isDepthPack(path)) return std::make_unique<app::DepthPackSource>(path);
#if VOXFUSE_WITH_IO
    return openImageSource(path);  // undistorted after the labels are attached (framesForEngine)
#else
    throw ConfigError(
        "this build has no image I/O (VOXFUSE_IO=OFF): the source must be synthetic[:N] or a depth pack (a folder with "
        "depth.bin.gz), not '" +
        path + "'");
#endif
}

}  // namespace

int main(int argc, char** argv) {
    app::useLongRunHeapPolicy();
    CLI::App cli{"Per-stage timings of the VoxFuse pipeline on a sequence."};
    std::string source_path, json_path = "voxfuse_bench.json", timings_path, trajectory_path, mesh_path;
    app::EngineOptions o;  // the map and tracking options voxfuse takes
#if VOXFUSE_WITH_IO
    app::LabelInputOptions labels;
#endif
    int max_frames = 0, warmup = 3, repeats = 3;
    bool mesh = false, cloud = false, render = false;
    float cloud_voxel_m = 0.f;
    OccupancySettings occupancy_settings;
    occupancy_settings.resolution_m = 0.f;  // off unless --occupancy
    cli.add_option("source", source_path,
                   "sequence (default: ../shared/data/tum_fr3_teddy_200, else the bundled data), or synthetic[:N] for "
                   "N frames of the "
                   "synthetic room rendered in memory");
    cli.add_option("--frames", max_frames, "at most N frames (0 = all)")->check(app::nonNegativeInt());
    cli.add_option("--warmup", warmup, "frames left out of the statistics")
        ->capture_default_str()
        ->check(app::nonNegativeInt());
    app::addMapOptions(cli, o);
#if VOXFUSE_WITH_IO
    app::addLabelOptions(cli, labels);
#endif
    app::addTrackingOptions(cli, o);
    cli.add_flag(
        "--render", render,
        "after each frame, render the model from the frame's camera (shaded, the depth camera's resolution, the image "
        "brought to the host), as the viewer does: timed as stage 'render', outside 'total'");
    cli.add_flag("--mesh", mesh,
                 "after the run, time marching cubes on the map (median of --repeats), its size and peak memory");
    cli.add_flag("--cloud", cloud, "after the run, time the point cloud extraction");
    cli.add_option("--cloud-voxel", cloud_voxel_m,
                   "also time downsampling the cloud to cells of this size (m); implies --cloud")
        ->check(app::floatIn(1e-4, 1000.0));
    cli.add_option("--repeats", repeats, "runs of each map output timed")
        ->capture_default_str()
        ->check(app::intIn(1, 100));
    cli.add_option("--occupancy", occupancy_settings.resolution_m,
                   "build an OctoMap with RES-metre cells beside the run; report its thread's throughput")
        ->check(app::floatIn(0.001, 10.0));
    cli.add_option("--occupancy-pixel-step", occupancy_settings.pixel_step, "occupancy: every Nth pixel in x and y")
        ->capture_default_str()
        ->check(app::intIn(1, 64));
    cli.add_option("--json", json_path, "where to write the JSON report")->capture_default_str();
    cli.add_option(
        "--timings", timings_path,
        "also write every frame's stage times and visible blocks to this JSON file (as voxfuse's timings.json)");
    cli.add_option("--trajectory", trajectory_path,
                   "also write the frames' poses to this file (TUM format, as voxfuse's trajectory.txt)");
    cli.add_option("--mesh-out", mesh_path,
                   "after the run, also write the map's mesh to this file (.ply, .obj or .stl)")
        ->check(app::meshFileName());
    app::addVersionFlag(cli, "voxfuse_bench");
    if (const auto status = app::parseCommandLine(cli, argc, argv, "voxfuse_bench")) return *status;
    app::noteGivenOptions(cli, o);

    app::interrupt::install("voxfuse_bench");
    return app::runReportingErrors("voxfuse_bench", [&] {
        app::checkEngineOptions(o);
        if (cli.count("--occupancy-pixel-step") > 0 && !(occupancy_settings.resolution_m > 0.f))
            throw ConfigError("--occupancy-pixel-step needs --occupancy");
        if (max_frames > 0 && max_frames <= warmup)
            throw ConfigError("--frames " + std::to_string(max_frames) + " leaves no frame after the " +
                              std::to_string(warmup) + " warm-up frames (--warmup)");
        requireWritable(json_path);  // before the run, not after it
        if (!timings_path.empty()) requireWritable(timings_path);
        if (!trajectory_path.empty()) requireWritable(trajectory_path);
        if (!mesh_path.empty()) requireWritable(mesh_path);
        if (source_path.empty()) source_path = defaultSource();
        std::unique_ptr<ImageSource> source = openSource(source_path);
#if VOXFUSE_WITH_IO
        app::attachLabelInput(source, source_path, labels, o.settings, o.wasGiven("--voxel"), "voxfuse_bench");
        source = framesForEngine(std::move(source), false);
#endif
        auto engine = MainEngine::create(o.settings.toEngineSettings(), source->calib());
        const MainEngineSettings& s = engine->settings();
        std::unique_ptr<OccupancyMapper> occupancy;
        if (occupancy_settings.resolution_m > 0.f) occupancy = std::make_unique<OccupancyMapper>(occupancy_settings);
        app::RunRecord record;
        record.source = source->description();
        record.settings = engine->settings();
        record.tracked = o.poses == "track";
        app::SequenceRunner runner(*source, *engine,
                                   record.tracked ? app::PoseSource::Tracker : app::PoseSource::GroundTruth, record,
                                   "voxfuse_bench");
        // Per pyramid level of the tracker, coarse to fine: "track L0 160x120", ...
        std::vector<std::string> level_names;
        std::map<std::string, std::vector<double>> level_samples, level_iterations;
        const Timer wall;
        Image<Vec4u8> rendered;
        while ((max_frames <= 0 || int(record.frames.size()) < max_frames) &&
               runner.processNext(app::interrupt::requested)) {
            if (render) {
                const Timer render_time;
                engine->renderLast(RenderMode::Shaded, rendered);
                record.frames.back().result.stages.push_back({"render", render_time.elapsedMs()});
            }
            const FrameResult& fr = runner.lastRecord().result;
            if (occupancy && fr.fused)
                occupancy->submit(engine->view().depth, engine->view().calib.depth, fr.T_world_camera);
            if (!record.tracked || int(record.frames.size()) <= warmup) continue;
            const TrackerStats& ts = engine->trackerStats();
            for (std::size_t l = 0; l < ts.levels.size(); ++l) {
                const std::string name = "  L" + std::to_string(l) + " " + std::to_string(ts.levels[l].width) + "x" +
                                         std::to_string(ts.levels[l].height);
                if (!level_samples.count(name)) level_names.push_back(name);
                level_samples[name].push_back(ts.levels[l].ms);
                level_iterations[name].push_back(ts.levels[l].iterations);
            }
        }
        record.wall_s = wall.elapsedMs() / 1000.0;
        record.interrupted = app::interrupt::requested();
        if (occupancy) occupancy->finish();
        record.peak_rss_mb = app::peakRssMb();
        record.scene_mb = double(engine->sceneBytes()) / (1024.0 * 1024.0);
        record.allocation = engine->allocationStats();
        if (int(record.frames.size()) <= warmup)
            throw ConfigError(std::to_string(record.frames.size()) + " frames were processed, no more than the " +
                              std::to_string(warmup) + " warm-up frames (--warmup): none is left for the statistics");

        std::vector<std::string> order;
        std::map<std::string, std::vector<double>> samples;
        for (std::size_t i = std::size_t(warmup); i < record.frames.size(); ++i) {
            for (const StageTime& st : record.frames[i].result.stages) {
                if (!samples.count(st.stage)) order.push_back(st.stage);
                samples[st.stage].push_back(st.ms);
            }
            samples["total"].push_back(record.frames[i].result.total_ms);
            if (render) {
                double render_ms = 0.0;
                for (const StageTime& st : record.frames[i].result.stages)
                    if (std::string(st.stage) == "render") render_ms = st.ms;
                samples["total+render"].push_back(record.frames[i].result.total_ms + render_ms);
            }
        }
        order.push_back("total");
        if (render) order.push_back("total+render");

        std::printf("VoxFuse benchmark: %s\n", record.source.c_str());
        const std::string device_text = s.device == Device::CUDA
                                            ? std::string("cuda: ") + device_memory::cudaDescription()
                                            : std::string(deviceName(s.device));
        std::printf(
            "  %s voxels, %s index, %.1f mm voxels, device %s, poses %s; %zu frames (%d warm-up frames left out)\n\n",
            toString(s.voxel_type), toString(s.index_type), 1000.0 * s.scene.voxel_size_m, device_text.c_str(),
            record.tracked ? (std::string("tracked (") + toString(s.tracker.kind) + ")").c_str() : "ground truth",
            record.frames.size(), warmup);
        std::printf("  %-12s %10s %10s %10s\n", "stage", "median ms", "mean ms", "p90 ms");
        std::map<std::string, StageSummary> summaries;
        for (const auto& name : order) {
            summaries[name] = summarise(samples[name]);
            std::printf("  %-12s %10.2f %10.2f %10.2f\n", name.c_str(), summaries[name].median_ms,
                        summaries[name].mean_ms, summaries[name].p90_ms);
            if (name != "track") continue;
            for (const auto& level : level_names) {  // the tracker's levels, indented under it
                summaries[level] = summarise(level_samples[level]);
                std::printf("  %-12s %10.2f %10.2f %10.2f   %.1f iterations (mean)\n", level.c_str(),
                            summaries[level].median_ms, summaries[level].mean_ms, summaries[level].p90_ms,
                            meanOf(level_iterations[level]));
            }
        }
        if (!source->groundTruth().empty()) {
            record.trajectory_error = evaluateTrajectory(record.trajectory, source->groundTruth());
            record.has_trajectory_error = record.trajectory_error.pairs >= 3;
        }
        const double engine_fps = 1000.0 / summaries["total"].median_ms;
        if (s.index_type == IndexType::Hash)
            std::printf("\n  hash: %d blocks in use, %lld allocation failures", record.allocation.blocks_allocated,
                        record.allocation.allocation_failures_total);
        if (record.has_trajectory_error) {
            const TrajectoryError& e = record.trajectory_error;
            const std::string rpe =
                e.rpe_pairs > 0 ? formatMillimetres(e.rpe_trans_m_per_s) + " mm/s" : "n/a (too short)";
            std::printf(
                "\n  ATE RMSE %.2f mm over %d poses (%.2f mm with the timestamps moved %+.1f ms, the best offset), RPE "
                "%s; "
                "%d frames failed tracking",
                1000.0 * e.ate_rmse_m, e.pairs, 1000.0 * e.ate_rmse_at_best_offset_m, 1000.0 * e.best_time_offset_s,
                rpe.c_str(), app::countQuality(record, TrackingQuality::Failed));
        }
        if (s.relocalisation.enabled)
            std::printf("\n  relocalisation: %d frames lost, %d relocalised after %d attempts",
                        app::countStatus(record, TrackingStatus::Lost),
                        app::countStatus(record, TrackingStatus::Relocalised),
                        app::countRelocalisationAttempts(record));
        std::printf("\n  engine frames/s (1000 / median total): %.1f", engine_fps);
        if (render) std::printf(", with a render per frame: %.1f", 1000.0 / summaries["total+render"].median_ms);
        std::printf("\n  wall frames/s (incl. decoding): %.1f\n  peak RSS: %.0f MB, scene: %.0f MB\n",
                    app::framesPerSecond(record), record.peak_rss_mb, record.scene_mb);

        // Swapping: blocks moved per frame (each way) and what stayed active.
        std::vector<double> swapped_in, swapped_out;
        int most_active = 0;
        for (std::size_t i = 0; i < record.frames.size(); ++i) {
            const AllocationStats& a = record.frames[i].result.allocation;
            swapped_in.push_back(a.blocks_swapped_in_this_frame);
            swapped_out.push_back(a.blocks_swapped_out_this_frame);
            most_active = std::max(most_active, a.blocks_allocated);
        }
        const auto most = [](const std::vector<double>& v) {
            return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
        };
        if (s.swap.enabled)
            std::printf(
                "  swapping: %d blocks stored in %s; per frame in %.1f (max %.0f), out %.1f (max %.0f), limit %d; "
                "at most %d of %d blocks active\n",
                record.allocation.blocks_stored, s.swap.swap_file.empty() ? "memory" : s.swap.swap_file.c_str(),
                meanOf(swapped_in), most(swapped_in), meanOf(swapped_out), most(swapped_out), s.swap.blocks_per_frame,
                most_active, s.hash.max_block_count);

        app::MeshingBench meshing;
        app::CloudBench cloud_bench;
        Mesh map_mesh;  // for --mesh-out: the timed extraction's, or one made for it below
        if (mesh) {
            meshing = app::benchMeshing(*engine, repeats, mesh_path.empty() ? nullptr : &map_mesh);
            app::printMeshing(meshing);
        }
        if (cloud || cloud_voxel_m > 0.f) {
            cloud_bench = app::benchCloud(*engine, repeats, cloud_voxel_m);
            app::printCloud(cloud_bench);
        }
        if (occupancy) app::printOccupancy(occupancy->stats(), occupancy->settings());

        app::Json j;
        j["source"] = record.source;
        j["interrupted"] = record.interrupted;
        j["voxel"] = toString(s.voxel_type);
        j["index"] = toString(s.index_type);
        j["voxel_size_m"] = double(s.scene.voxel_size_m);
        j["device"] = deviceName(s.device);
        if (s.device == Device::CUDA) j["gpu"] = device_memory::cudaDescription();
        j["frames"] = int(record.frames.size());
        j["warmup_frames"] = warmup;
        app::Json& stages = j["stages"] = app::Json::object();
        for (const auto& name : order)
            stages[name] = {{"median_ms", summaries[name].median_ms},
                            {"mean_ms", summaries[name].mean_ms},
                            {"p90_ms", summaries[name].p90_ms}};
        app::Json& levels = j["tracker_levels"] = app::Json::object();
        for (const auto& level : level_names) levels[level.substr(2)] = summaries[level].median_ms;
        app::Json& iterations = j["tracker_iterations"] =
            app::Json::object();  // mean Gauss-Newton iterations per frame
        for (const auto& level : level_names) iterations[level.substr(2)] = meanOf(level_iterations[level]);
        if (record.has_trajectory_error) {
            j["ate_rmse_m"] = record.trajectory_error.ate_rmse_m;
            j["ate_best_time_offset_s"] = record.trajectory_error.best_time_offset_s;
            j["ate_rmse_at_best_time_offset_m"] = record.trajectory_error.ate_rmse_at_best_offset_m;
            if (record.trajectory_error.rpe_pairs > 0)
                j["rpe_trans_m_per_s"] = record.trajectory_error.rpe_trans_m_per_s;
        }
        j["tracking_failed_frames"] = app::countQuality(record, TrackingQuality::Failed);
        j["frames_lost"] = app::countStatus(record, TrackingStatus::Lost);
        j["relocalisation_attempts"] = app::countRelocalisationAttempts(record);
        j["relocalisations"] = app::countStatus(record, TrackingStatus::Relocalised);
        j["engine_fps"] = engine_fps;
        if (render) j["engine_fps_with_render"] = 1000.0 / summaries["total+render"].median_ms;
        j["wall_fps"] = app::framesPerSecond(record);
        j["peak_rss_mb"] = record.peak_rss_mb;
        j["scene_mb"] = record.scene_mb;
        j["blocks_allocated"] = record.allocation.blocks_allocated;
        if (s.swap.enabled) {
            app::Json& swapping = j["swapping"];
            swapping["swap_file"] = s.swap.swap_file;
            swapping["active_block_limit"] = s.hash.max_block_count;
            swapping["most_blocks_active"] = most_active;
            swapping["blocks_stored"] = record.allocation.blocks_stored;
            swapping["blocks_per_frame_limit"] = s.swap.blocks_per_frame;
            swapping["mean_swapped_in_per_frame"] = meanOf(swapped_in);
            swapping["most_swapped_in_per_frame"] = most(swapped_in);
            swapping["mean_swapped_out_per_frame"] = meanOf(swapped_out);
            swapping["most_swapped_out_per_frame"] = most(swapped_out);
        }
        j["allocation_failures"] = (long long)record.allocation.allocation_failures_total;
        if (mesh) j["meshing"] = app::meshingJson(meshing);
        if (cloud || cloud_voxel_m > 0.f) j["point_cloud"] = app::cloudJson(cloud_bench);
        if (occupancy) j["occupancy"] = app::occupancyJson(occupancy->stats(), occupancy->settings());
        app::writeJsonFile(json_path, j);
        std::printf("  JSON: %s\n", json_path.c_str());
        if (!timings_path.empty()) {
            app::writeTimingsJson(timings_path, record);
            std::printf("  per-frame timings: %s\n", timings_path.c_str());
        }
        if (!trajectory_path.empty()) {
            writeTumTrajectory(trajectory_path, record.trajectory);
            std::printf("  trajectory: %s\n", trajectory_path.c_str());
        }
        if (!mesh_path.empty()) {
            if (!mesh) engine->extractMesh(map_mesh);
            writeMesh(mesh_path, map_mesh);
            std::printf("  mesh: %s (%zu triangles)\n", mesh_path.c_str(), map_mesh.triangles.size());
        }
        return app::interrupt::exitStatus();
    });
}
