#include "RunRecord.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "JsonWriter.h"
#include "Statistics.h"
#include "voxfuse/core/Error.h"

namespace voxfuse::app {
namespace {

// Stage names in pipeline order, as they first appear.
std::vector<std::string> stageNames(const RunRecord& run) {
    std::vector<std::string> names;
    for (const auto& f : run.frames)
        for (const auto& s : f.result.stages)
            if (std::find(names.begin(), names.end(), s.stage) == names.end()) names.push_back(s.stage);
    return names;
}

std::map<std::string, double> stageMedians(const RunRecord& run) {
    std::map<std::string, std::vector<double>> samples;
    for (const auto& f : run.frames)
        for (const auto& s : f.result.stages) samples[s.stage].push_back(s.ms);
    std::map<std::string, double> medians;
    for (auto& [name, v] : samples) medians[name] = median(v);
    return medians;
}

std::ofstream openForWriting(const std::string& path) {
    std::ofstream out(path);
    if (!out) throw IoError(path, "cannot open for writing");
    return out;
}

}  // namespace

int countQuality(const RunRecord& run, TrackingQuality quality) {
    int n = 0;
    for (const auto& f : run.frames) n += f.result.quality == quality ? 1 : 0;
    return n;
}

int countStatus(const RunRecord& run, TrackingStatus status) {
    int n = 0;
    for (const auto& f : run.frames) n += f.result.status == status ? 1 : 0;
    return n;
}

int countRelocalisationAttempts(const RunRecord& run) {
    int n = 0;
    for (const auto& f : run.frames) n += f.result.relocalisation_tried ? 1 : 0;
    return n;
}

double medianTotalMs(const RunRecord& run) {
    std::vector<double> totals;
    for (const auto& f : run.frames) totals.push_back(f.result.total_ms);
    return median(totals);
}

double framesPerSecond(const RunRecord& run) { return run.wall_s > 0.0 ? double(run.frames.size()) / run.wall_s : 0.0; }

void writeTimingsJson(const std::string& path, const RunRecord& run) {
    std::ofstream out = openForWriting(path);
    JsonWriter j(out);
    const auto names = stageNames(run);
    const auto medians = stageMedians(run);
    j.beginObject();
    j.beginObject("median_ms");
    for (const auto& n : names) j.value(n.c_str(), medians.at(n));
    j.value("total", medianTotalMs(run));
    j.endObject();
    j.beginArray("frames");
    for (const auto& f : run.frames) {
        j.beginObject();
        j.value("index", f.index);
        j.value("timestamp", f.timestamp_s);
        j.value("fused", f.result.fused);
        j.value("tracking", toString(f.result.quality));
        j.value("status", toString(f.result.status));
        j.value("keyframes", f.result.keyframes);
        if (run.tracked) {
            j.value("inlier_ratio", double(f.result.tracking.inlier_ratio));
            j.value("residual", double(f.result.tracking.residual_m));
        }
        for (const auto& s : f.result.stages) j.value(s.stage, s.ms);
        j.value("total", f.result.total_ms);
        if (run.settings.index_type == IndexType::Hash) {
            j.value("visible_blocks", f.result.allocation.visible_blocks);
            j.value("allocation_failures", f.result.allocation.allocation_failures_this_frame);
        }
        if (run.settings.swap.enabled) {
            j.value("swapped_in", f.result.allocation.blocks_swapped_in_this_frame);
            j.value("swapped_out", f.result.allocation.blocks_swapped_out_this_frame);
            j.value("blocks_stored", f.result.allocation.blocks_stored);
        }
        j.endObject();
    }
    j.endArray();
    j.endObject();
}

void writeSummaryJson(const std::string& path, const RunRecord& run) {
    std::ofstream out = openForWriting(path);
    JsonWriter j(out);
    int fused = 0;
    for (const auto& f : run.frames) fused += f.result.fused ? 1 : 0;
    j.beginObject();
    j.value("source", run.source);
    j.value("frames", int(run.frames.size()));
    j.value("frames_fused", fused);
    j.value("frames_without_pose", run.frames_without_pose);
    j.value("frames_unreadable", run.frames_unreadable);
    j.value("frames_dropped", run.frames_dropped);
    if (run.has_labels) j.value("frames_with_labels", run.frames_with_labels);
    j.value("poses", run.tracked ? "tracked" : "groundtruth");
    j.value("tracking_poor_frames", countQuality(run, TrackingQuality::Poor));
    j.value("tracking_failed_frames", countQuality(run, TrackingQuality::Failed));
    j.value("frames_lost", countStatus(run, TrackingStatus::Lost));
    j.value("relocalisation_attempts", countRelocalisationAttempts(run));
    j.value("relocalisations", countStatus(run, TrackingStatus::Relocalised));
    j.value("keyframes", run.frames.empty() ? 0 : run.frames.back().result.keyframes);
    if (run.has_trajectory_error) {
        const TrajectoryError& e = run.trajectory_error;
        j.value("ate_rmse_m", e.ate_rmse_m);
        j.value("ate_mean_m", e.ate_mean_m);
        j.value("ate_median_m", e.ate_median_m);
        j.value("ate_max_m", e.ate_max_m);
        j.value("ate_pairs", e.pairs);
        j.value("rpe_trans_m_per_s", e.rpe_trans_m_per_s);
        j.value("rpe_rot_deg_per_s", e.rpe_rot_deg_per_s);
        j.value("rpe_pairs", e.rpe_pairs);
    }
    j.value("median_ms", medianTotalMs(run));
    j.value("fps", framesPerSecond(run));
    j.value("wall_s", run.wall_s);
    j.value("peak_rss_mb", run.peak_rss_mb);
    j.value("scene_mb", run.scene_mb);
    j.value("blocks_allocated", run.allocation.blocks_allocated);
    j.value("allocation_failures", (long long)run.allocation.allocation_failures_total);
    j.value("blocks_removed", (long long)run.allocation.blocks_removed_total);
    if (run.settings.swap.enabled) {
        int most_in = 0, most_out = 0;
        long long moved = 0;
        for (const auto& f : run.frames) {
            most_in = std::max(most_in, f.result.allocation.blocks_swapped_in_this_frame);
            most_out = std::max(most_out, f.result.allocation.blocks_swapped_out_this_frame);
            moved += f.result.allocation.blocks_swapped_in_this_frame + f.result.allocation.blocks_swapped_out_this_frame;
        }
        j.beginObject("swapping");
        j.value("blocks_stored", run.allocation.blocks_stored);
        j.value("active_block_limit", run.settings.hash.max_block_count);
        j.value("blocks_per_frame_limit", run.settings.swap.blocks_per_frame);
        j.value("most_swapped_in_per_frame", most_in);
        j.value("most_swapped_out_per_frame", most_out);
        j.value("blocks_moved", moved);
        j.value("swap_file", run.settings.swap.swap_file);
        j.endObject();
    }
    if (!run.map_loaded.empty()) j.value("map_loaded", run.map_loaded);
    if (!run.map_saved.empty()) j.value("map_saved", run.map_saved);
    j.beginObject("settings");
    j.value("voxel", toString(run.settings.voxel_type));
    j.value("index", toString(run.settings.index_type));
    j.value("device", deviceName(run.settings.device));
    if (run.settings.device == Device::CUDA) j.value("gpu", device_memory::cudaDescription());
    j.value("voxel_size_m", double(run.settings.scene.voxel_size_m));
    j.value("mu_m", double(run.settings.scene.mu_m));
    j.value("max_weight", run.settings.scene.max_weight);
    j.value("min_depth_m", double(run.settings.scene.view_frustum_min_m));
    j.value("max_depth_m", double(run.settings.scene.view_frustum_max_m));
    if (voxelTypeHasLabels(run.settings.voxel_type))
        j.value("label_update", run.settings.scene.label_update == LabelUpdate::Vote ? "vote" : "probabilistic");
    if (run.tracked) {
        j.value("tracker", toString(run.settings.tracker.kind));
        std::string levels;
        for (const auto& l : run.settings.tracker.levels) levels += char(l.motion);
        j.value("tracker_levels", levels);
        j.value("relocalisation", run.settings.relocalisation.enabled);
    }
    j.endObject();
    j.endObject();
}

std::string summaryText(const RunRecord& run, const std::string& out_dir) {
    std::ostringstream s;
    int fused = 0;
    for (const auto& f : run.frames) fused += f.result.fused ? 1 : 0;
    char line[256];
    s << "VoxFuse run\n";
    s << "  source       " << run.source << "\n";
    std::snprintf(line, sizeof line, "  frames       %zu processed, %d fused, %d without pose, %d unreadable, %d dropped (live)\n",
                  run.frames.size(), fused, run.frames_without_pose, run.frames_unreadable, run.frames_dropped);
    s << line;
    if (run.frames.empty()) {
        // A map written out without frames: nothing was tracked.
    } else if (run.tracked) {
        std::snprintf(line, sizeof line, "  tracking     %s tracker: %d good, %d poor, %d failed (not fused)\n", toString(run.settings.tracker.kind),
                      int(run.frames.size()) - countQuality(run, TrackingQuality::Poor) - countQuality(run, TrackingQuality::Failed),
                      countQuality(run, TrackingQuality::Poor), countQuality(run, TrackingQuality::Failed));
        s << line;
        if (run.settings.relocalisation.enabled || countStatus(run, TrackingStatus::Lost) > 0) {
            std::snprintf(line, sizeof line, "  lost         %d frames without a pose (not fused), %d relocalised after %d attempts%s\n",
                          countStatus(run, TrackingStatus::Lost), countStatus(run, TrackingStatus::Relocalised),
                          countRelocalisationAttempts(run), run.settings.relocalisation.enabled ? "" : " (relocalisation off)");
            s << line;
        }
    } else {
        s << "  poses        ground truth\n";
    }
    if (run.has_trajectory_error) {
        const TrajectoryError& e = run.trajectory_error;
        std::snprintf(line, sizeof line, "  accuracy     ATE RMSE %.1f mm (median %.1f, max %.1f, %d poses), ", 1000.0 * e.ate_rmse_m,
                      1000.0 * e.ate_median_m, 1000.0 * e.ate_max_m, e.pairs);
        s << line;
        if (e.rpe_pairs > 0) {
            std::snprintf(line, sizeof line, "RPE %.1f mm/s %.2f deg/s\n", 1000.0 * e.rpe_trans_m_per_s, e.rpe_rot_deg_per_s);
            s << line;
        } else {
            s << "RPE n/a (sequence shorter than its 1 s step)\n";
        }
    }
    if (run.has_labels) {
        std::snprintf(line, sizeof line, "  labels       %d of %zu frames had a label image (%s update)\n", run.frames_with_labels,
                      run.frames.size(), run.settings.scene.label_update == LabelUpdate::Vote ? "vote" : "probabilistic");
        s << line;
    }
    std::snprintf(line, sizeof line, "  volume       %s voxels, %s index, %.1f mm voxels, mu %.1f mm, %.0f MB\n",
                  toString(run.settings.voxel_type), toString(run.settings.index_type), 1000.0 * run.settings.scene.voxel_size_m,
                  1000.0 * run.settings.scene.mu_m, run.scene_mb);
    s << line;
    std::snprintf(line, sizeof line, "  speed        %.1f ms per frame (median, engine only), %.1f frames/s overall\n",
                  medianTotalMs(run), framesPerSecond(run));
    s << line;
    if (run.settings.swap.enabled) {
        std::snprintf(line, sizeof line, "  swapping     %d blocks stored in %s, at most %d active, at most %d moved each way per frame\n",
                      run.allocation.blocks_stored, run.settings.swap.swap_file.empty() ? "memory" : run.settings.swap.swap_file.c_str(),
                      run.settings.hash.max_block_count, run.settings.swap.blocks_per_frame);
        s << line;
    }
    if (run.settings.index_type == IndexType::Hash) {
        std::snprintf(line, sizeof line, "  hash         %d blocks in use (%d backed by memory), %lld removed, %lld could not be allocated%s\n",
                      run.allocation.blocks_allocated, run.allocation.block_capacity, run.allocation.blocks_removed_total,
                      run.allocation.allocation_failures_total,
                      run.allocation.allocation_failures_total > 0 ? " (raise --max-blocks / the hash size)" : "");
        s << line;
    }
    s << "  stages (median ms):";
    const auto medians = stageMedians(run);
    for (const auto& n : stageNames(run)) {
        std::snprintf(line, sizeof line, " %s %.1f", n.c_str(), medians.at(n));
        s << line;
    }
    s << "\n";
    if (!run.map_loaded.empty() || !run.map_saved.empty())
        s << "  map          " << (run.map_loaded.empty() ? "" : "continued " + run.map_loaded + (run.map_saved.empty() ? "" : ", "))
          << (run.map_saved.empty() ? "" : "saved to " + run.map_saved) << "\n";
    std::snprintf(line, sizeof line, "  peak memory  %.0f MB\n", run.peak_rss_mb);
    s << line;
    s << "  outputs      " << out_dir << "/ (trajectory.txt, timings.json, summary.json, render_*.png and any map outputs)\n";
    return s.str();
}

}  // namespace voxfuse::app
