#include "RunRecord.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <variant>

#include "JsonFile.h"
#include "Statistics.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/PipelineSettings.h"

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

}  // namespace

int countQuality(const RunRecord& run, TrackingQuality quality) {
    int n = 0;
    for (const auto& f : run.frames) n += f.result.quality == quality ? 1 : 0;
    return n;
}

namespace {
std::string metres(float v) {
    std::ostringstream s;
    s << v;
    return s.str();
}
}  // namespace

int countFused(const RunRecord& run) {
    int n = 0;
    for (const auto& f : run.frames) n += f.result.fused ? 1 : 0;
    return n;
}

std::string nothingFusedReason(const RunRecord& run) {
    if (run.interrupted || run.frames.empty()) return "";
    const std::string frames = std::to_string(run.frames.size()) + (run.frames.size() == 1 ? " frame" : " frames");
    if (countFused(run) == 0)
        return "none of the " + frames + " processed was fused (" +
               std::to_string(countQuality(run, TrackingQuality::Failed)) + " failed to track, " +
               std::to_string(countStatus(run, TrackingStatus::Lost)) + " without a pose): " +
               (run.map_loaded.empty() ? "the map holds nothing of "
                                       : "nothing was added to the map loaded from " + run.map_loaded + " from ") +
               run.source + "; is the calibration's depth scale right, and does the depth reach " +
               metres(run.settings.scene.view_frustum_min_m) + " to " + metres(run.settings.scene.view_frustum_max_m) +
               " m?";
    const AllocationStats& a = run.allocation;
    if (run.settings.index_type == IndexType::Hash && a.blocks_allocated + a.blocks_stored == 0)
        return "the map is empty after " + frames + ": no depth sample lay between " +
               metres(run.settings.scene.view_frustum_min_m) + " and " + metres(run.settings.scene.view_frustum_max_m) +
               " m (the view frustum) once converted; is the calibration's depth scale right?";
    return "";
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
    const auto medians = stageMedians(run);
    Json j;
    Json& median_ms = j["median_ms"] = Json::object();
    for (const auto& n : stageNames(run)) median_ms[n] = medians.at(n);
    median_ms["total"] = medianTotalMs(run);
    Json& frames = j["frames"] = Json::array();
    for (const auto& f : run.frames) {
        Json frame;
        frame["index"] = f.index;
        frame["timestamp"] = f.timestamp_s;
        frame["fused"] = f.result.fused;
        if (run.tracked) {  // with given poses there is no tracking to report
            frame["tracking"] = toString(f.result.quality);
            frame["status"] = toString(f.result.status);
            frame["keyframes"] = f.result.keyframes;
            frame["inlier_ratio"] = double(f.result.tracking.inlier_ratio);
            frame["residual"] = double(f.result.tracking.residual_m);
            frame["condition"] = double(f.result.tracking.condition);
            if (f.result.tracking.translation_constraint >= 0.f)
                frame["translation_constraint"] = double(f.result.tracking.translation_constraint);
        }
        for (const auto& s : f.result.stages) frame[s.stage] = s.ms;
        frame["total"] = f.result.total_ms;
        if (run.settings.index_type == IndexType::Hash) {
            frame["visible_blocks"] = f.result.allocation.visible_blocks;
            frame["allocation_failures"] = f.result.allocation.allocation_failures_this_frame;
        }
        if (run.settings.swap.enabled) {
            frame["swapped_in"] = f.result.allocation.blocks_swapped_in_this_frame;
            frame["swapped_out"] = f.result.allocation.blocks_swapped_out_this_frame;
            frame["blocks_stored"] = f.result.allocation.blocks_stored;
        }
        frames.push_back(std::move(frame));
    }
    writeJsonFile(path, j);
}

void writeSummaryJson(const std::string& path, const RunRecord& run) {
    const int fused = countFused(run);
    Json j;
    j["source"] = run.source;
    j["interrupted"] = run.interrupted;
    j["frames"] = int(run.frames.size());
    j["frames_fused"] = fused;
    j["depth_samples_out_of_range"] = run.depth_samples_out_of_range;
    j["color_samples_out_of_range"] = run.color_samples_out_of_range;
    j["frames_with_samples_out_of_range"] = run.frames_with_samples_out_of_range;
    j["frames_without_pose"] = run.frames_without_pose;
    j["frames_unreadable"] = run.frames_unreadable;
    j["frames_dropped"] = run.frames_dropped;
    if (run.has_labels) j["frames_with_labels"] = run.frames_with_labels;
    j["poses"] = run.tracked ? "tracked" : "groundtruth";
    j["tracking_poor_frames"] = countQuality(run, TrackingQuality::Poor);
    j["tracking_failed_frames"] = countQuality(run, TrackingQuality::Failed);
    j["frames_lost"] = countStatus(run, TrackingStatus::Lost);
    j["relocalisation_attempts"] = countRelocalisationAttempts(run);
    j["relocalisations"] = countStatus(run, TrackingStatus::Relocalised);
    j["keyframes"] = run.frames.empty() ? 0 : run.frames.back().result.keyframes;
    if (run.has_trajectory_error) {
        const TrajectoryError& e = run.trajectory_error;
        j["ate_rmse_m"] = e.ate_rmse_m;
        j["ate_mean_m"] = e.ate_mean_m;
        j["ate_median_m"] = e.ate_median_m;
        j["ate_max_m"] = e.ate_max_m;
        j["ate_pairs"] = e.pairs;
        j["rpe_trans_m_per_s"] = e.rpe_trans_m_per_s;
        j["rpe_rot_deg_per_s"] = e.rpe_rot_deg_per_s;
        j["rpe_pairs"] = e.rpe_pairs;
        j["ate_best_time_offset_s"] = e.best_time_offset_s;
        j["ate_rmse_at_best_time_offset_m"] = e.ate_rmse_at_best_offset_m;
        if (run.settings.submaps.enabled) j["ate_online_rmse_m"] = run.trajectory_error_online.ate_rmse_m;
    }
    if (run.settings.submaps.enabled) {
        j["submaps"] = run.submaps;
        nlohmann::json loops = nlohmann::json::array();
        for (const LoopClosure& l : run.loop_closures) {
            const bool known = l.frame >= 0 && l.frame < int(run.frames.size());
            loops.push_back({{"frame", known ? run.frames[l.frame].index : -1},
                             {"from_submap", l.from_submap},
                             {"to_submap", l.to_submap},
                             {"residual_m", l.residual_m},
                             {"inlier_ratio", l.inlier_ratio},
                             {"chi2", l.chi2},
                             {"rejected", l.rejected}});
        }
        j["loop_closures"] = loops;
        j["pose_graph"] = {{"solves", run.pose_graph.solves},
                           {"total_ms", run.pose_graph.total_ms},
                           {"max_ms", run.pose_graph.max_ms}};
    }
    j["median_ms"] = medianTotalMs(run);
    j["fps"] = framesPerSecond(run);
    j["wall_s"] = run.wall_s;
    j["peak_rss_mb"] = run.peak_rss_mb;
    j["scene_mb"] = run.scene_mb;
    if (run.mesh_ms >= 0.0) j["mesh_ms"] = run.mesh_ms;
    j["blocks_allocated"] = run.allocation.blocks_allocated;
    j["allocation_failures"] = (long long)run.allocation.allocation_failures_total;
    j["blocks_removed"] = (long long)run.allocation.blocks_removed_total;
    if (run.settings.swap.enabled) {
        int most_in = 0, most_out = 0;
        long long moved = 0;
        for (const auto& f : run.frames) {
            most_in = std::max(most_in, f.result.allocation.blocks_swapped_in_this_frame);
            most_out = std::max(most_out, f.result.allocation.blocks_swapped_out_this_frame);
            moved +=
                f.result.allocation.blocks_swapped_in_this_frame + f.result.allocation.blocks_swapped_out_this_frame;
        }
        Json& swapping = j["swapping"];
        swapping["blocks_stored"] = run.allocation.blocks_stored;
        swapping["active_block_limit"] = run.settings.hash.max_block_count;
        swapping["blocks_per_frame_limit"] = run.settings.swap.blocks_per_frame;
        swapping["most_swapped_in_per_frame"] = most_in;
        swapping["most_swapped_out_per_frame"] = most_out;
        swapping["blocks_moved"] = moved;
        swapping["swap_file"] = run.settings.swap.swap_file;
    }
    if (!run.map_loaded.empty()) j["map_loaded"] = run.map_loaded;
    if (!run.map_saved.empty()) j["map_saved"] = run.map_saved;
    // Every setting of the table by its name, as the engine used it (an automatic block ceiling as the
    // value chosen, the tracker written out level by level), and what a tracker settings file changed
    // that the table does not hold but the poses depend on.
    Json& settings = j["settings"];
    const PipelineSettings used = PipelineSettings::of(run.settings);
    for (const SettingRow& row : pipelineSettingRows())
        std::visit(
            [&](auto member) {
                const auto& value = used.*member;
                using T = std::decay_t<decltype(value)>;
                if constexpr (std::is_same_v<T, float>) {
                    settings[row.name] = floatAsDecimal(value);
                } else if constexpr (std::is_same_v<T, std::vector<float>>) {
                    Json& list = settings[row.name] = Json::array();
                    for (const float v : value) list.push_back(floatAsDecimal(v));
                } else {
                    settings[row.name] = value;
                }
            },
            row.member);
    settings["poses"] = run.tracked ? "track" : "groundtruth";
    if (run.settings.device == Device::CUDA) settings["gpu"] = device_memory::cudaDescription();
    // It changes the poses without changing max_depth: a run must say which depths it tracked on.
    settings["max_tracking_depth_m"] = floatAsDecimal(run.settings.tracker.max_tracking_depth_m);
    // rgbd reads depths beyond max_depth too (its far field): 0 keyframes means it did not.
    settings["far_field_keyframes"] = run.settings.tracker.far_field_keyframes;
    j["outputs"] = run.outputs;
    writeJsonFile(path, j);
}

std::string summaryText(const RunRecord& run, const std::string& out_dir) {
    std::ostringstream s;
    const int fused = countFused(run);
    char line[256];
    s << (run.interrupted ? "VoxFuse run (interrupted: the outputs hold the frames done)\n" : "VoxFuse run\n");
    s << "  source       " << run.source << "\n";
    std::snprintf(line, sizeof line,
                  "  frames       %zu processed, %d fused, %d without pose, %d unreadable, %d dropped (live)\n",
                  run.frames.size(), fused, run.frames_without_pose, run.frames_unreadable, run.frames_dropped);
    s << line;
    if (run.frames.empty()) {
        // A map written out without frames: nothing was tracked.
    } else if (run.tracked) {
        std::snprintf(line, sizeof line, "  tracking     %s tracker: %d good, %d poor, %d failed (not fused)\n",
                      toString(run.settings.tracker.kind),
                      int(run.frames.size()) - countQuality(run, TrackingQuality::Poor) -
                          countQuality(run, TrackingQuality::Failed),
                      countQuality(run, TrackingQuality::Poor), countQuality(run, TrackingQuality::Failed));
        s << line;
        if (run.settings.relocalisation.enabled || countStatus(run, TrackingStatus::Lost) > 0) {
            std::snprintf(line, sizeof line,
                          "  lost         %d frames without a pose (not fused), %d relocalised after %d attempts%s\n",
                          countStatus(run, TrackingStatus::Lost), countStatus(run, TrackingStatus::Relocalised),
                          countRelocalisationAttempts(run),
                          run.settings.relocalisation.enabled ? "" : " (relocalisation off)");
            s << line;
        }
    } else {
        s << "  poses        ground truth\n";
    }
    if (run.settings.submaps.enabled) {
        int rejected = 0;
        for (const LoopClosure& l : run.loop_closures) rejected += l.rejected ? 1 : 0;
        std::snprintf(line, sizeof line, "  submaps      %d, %zu loop closures (%d rejected by the pose graph)",
                      run.submaps, run.loop_closures.size(), rejected);
        s << line;
        if (run.has_trajectory_error) {
            std::snprintf(line, sizeof line, "; ATE RMSE as tracked %.1f mm",
                          1000.0 * run.trajectory_error_online.ate_rmse_m);
            s << line;
        }
        s << "\n";
        std::snprintf(line, sizeof line,
                      "  pose graph   %d solves off the frame loop, %.1f ms in all, at most %.1f ms\n",
                      run.pose_graph.solves, run.pose_graph.total_ms, run.pose_graph.max_ms);
        s << line;
    }
    if (run.has_trajectory_error) {
        const TrajectoryError& e = run.trajectory_error;
        std::snprintf(line, sizeof line, "  accuracy     ATE RMSE %.1f mm (median %.1f, max %.1f, %d poses), ",
                      1000.0 * e.ate_rmse_m, 1000.0 * e.ate_median_m, 1000.0 * e.ate_max_m, e.pairs);
        s << line;
        if (e.rpe_pairs > 0) {
            std::snprintf(line, sizeof line, "RPE %.1f mm/s %.2f deg/s\n", 1000.0 * e.rpe_trans_m_per_s,
                          e.rpe_rot_deg_per_s);
            s << line;
        } else {
            s << "RPE n/a (sequence shorter than its 1 s step)\n";
        }
        if (std::isfinite(e.best_time_offset_s)) {
            std::snprintf(line, sizeof line,
                          "  clocks       best offset %+.1f ms (frame times against the ground truth's, within %.0f "
                          "ms): ATE RMSE %.1f mm\n",
                          1000.0 * e.best_time_offset_s, 1000.0 * TrajectoryErrorOptions().max_time_offset_s,
                          1000.0 * e.ate_rmse_at_best_offset_m);
            s << line;
        }
    }
    if (run.has_labels) {
        std::snprintf(line, sizeof line, "  labels       %d of %zu frames had a label image (%s update)\n",
                      run.frames_with_labels, run.frames.size(),
                      run.settings.scene.label_update == LabelUpdate::Vote ? "vote" : "probabilistic");
        s << line;
    }
    std::snprintf(line, sizeof line, "  volume       %s voxels, %s index, %.1f mm voxels, mu %.1f mm, %.0f MB\n",
                  toString(run.settings.voxel_type), toString(run.settings.index_type),
                  1000.0 * run.settings.scene.voxel_size_m, 1000.0 * run.settings.scene.mu_m, run.scene_mb);
    s << line;
    std::snprintf(line, sizeof line, "  speed        %.1f ms per frame (median, engine only), %.1f frames/s overall\n",
                  medianTotalMs(run), framesPerSecond(run));
    s << line;
    if (run.settings.swap.enabled) {
        std::snprintf(line, sizeof line,
                      "  swapping     %d blocks stored in %s, at most %d active, at most %d moved each way per frame\n",
                      run.allocation.blocks_stored,
                      run.settings.swap.swap_file.empty() ? "memory" : run.settings.swap.swap_file.c_str(),
                      run.settings.hash.max_block_count, run.settings.swap.blocks_per_frame);
        s << line;
    }
    if (run.settings.index_type == IndexType::Hash) {
        std::snprintf(
            line, sizeof line,
            "  hash         %d blocks in use (%d backed by memory), %lld removed, %lld could not be allocated%s\n",
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
        s << "  map          "
          << (run.map_loaded.empty() ? "" : "continued " + run.map_loaded + (run.map_saved.empty() ? "" : ", "))
          << (run.map_saved.empty() ? "" : "saved to " + run.map_saved) << "\n";
    std::snprintf(line, sizeof line, "  peak memory  %.0f MB\n", run.peak_rss_mb);
    s << line;
    s << "  outputs      " << out_dir << "/:";
    const std::size_t shown = std::min<std::size_t>(run.outputs.size(), 6);
    for (std::size_t i = 0; i < shown; ++i) s << " " << run.outputs[i];
    if (run.outputs.size() > shown) s << " and " << run.outputs.size() - shown << " more";
    s << "\n";
    return s.str();
}

}  // namespace voxfuse::app
