// The pipeline's settings table: one row per setting (range, unit, help), the checks made from it, and
// the translation into the engine's settings.

#include "voxfuse/engines/PipelineSettings.h"

#include <charconv>
#include <climits>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "voxfuse/core/Error.h"
#include "voxfuse/engines/TrackerSettings.h"

namespace voxfuse {

namespace {

using P = PipelineSettings;
constexpr double kIntMax = double(INT_MAX);
constexpr double kMostBlocks = double(1 << 22);  // the block array's limit (automaticMaxBlockCount)

std::string existingFileProblem(const std::string& path) {
    if (path.empty()) return {};
    // Anything that reads as a file: also a pipe, as <(...) gives one.
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) return "'" + path + "' does not exist";
    if (std::filesystem::is_directory(path, ec)) return "'" + path + "' is a folder, not a file";
    return {};
}

std::string levelsProblem(const std::string& levels) {
    if (levels.empty()) return {};
    if (levels.size() > 8) return "'" + levels + "': need 1 to 8 levels";
    if (levels.find_first_not_of("rtb") != std::string::npos) return "'" + levels + "': level types are r, t or b";
    return {};
}

const std::vector<SettingRow> kRows = {
    // name, member, group, unit, min, max, min_open, list_size, choices, help, cli form, former name, check
    {"voxel", &P::voxel, SettingGroup::Map, "", 0, 0, false, 0, "s f s_rgb f_rgb s_label s_rgb_label",
     "voxel type: SDF as int16 (s) or float (f), with colour (rgb) and classes (label); on the command line "
     "s_rgb_label by default with --labels"},
    {"index", &P::index, SettingGroup::Map, "", 0, 0, false, 0, "hash dense",
     "voxel index: the voxel block hash (memory follows the scene) or one dense box of voxels"},
    {"device", &P::device, SettingGroup::Map, "", 0, 0, false, 0, "cpu cuda",
     "where the frame loop runs and the map lives: cpu, or cuda for the GPU (image processing, tracking, fusion, "
     "raycast, meshes)"},
    {"voxel_size", &P::voxel_size, SettingGroup::Map, "m", 0, 1, true, 0, "", "voxel edge"},
    {"mu", &P::mu, SettingGroup::Map, "m", 0, 10, true, 0, "", "truncation band"},
    {"max_weight", &P::max_weight, SettingGroup::Map, "", 1, 255, false, 0, "", "cap on the per-voxel weight"},
    {"min_depth", &P::min_depth, SettingGroup::Map, "m", 0, 1000, false, 0, "", "depth below this is ignored"},
    {"max_depth", &P::max_depth, SettingGroup::Map, "m", 0, 1000, true, 0, "", "depth beyond this is ignored"},
    {"depth_gap_tolerance", &P::depth_gap_tolerance, SettingGroup::Map, "", 0, 0.5, false, 0, "",
     "fill a pixel without depth whose two neighbours (left-right, else up-down) agree within this fraction of "
     "their depth with their mean; 0 = never"},
    {"max_blocks", &P::max_blocks, SettingGroup::Map, "", 0, kMostBlocks, false, 0, "",
     "hash: most 8^3 voxel blocks (memory grows on demand up to this); 0 = automatic: as many as the hash has "
     "entries and 3/4 of the device's free memory holds (on the GPU with room for the copy a growth makes)"},
    {"hash_buckets", &P::hash_buckets, SettingGroup::Map, "", 1, kIntMax, false, 0, "",
     "hash: ordered buckets the table starts with"},
    {"hash_excess", &P::hash_excess, SettingGroup::Map, "", 0, kIntMax, false, 0, "",
     "hash: entries in the excess list it starts with"},
    {"hash_max_buckets", &P::hash_max_buckets, SettingGroup::Map, "", 0, kIntMax, false, 0, "",
     "hash: the table doubles, its excess list with it, rather than hold more blocks than 0.4 of its buckets, up "
     "to this many buckets; at most hash_buckets: a fixed table"},
    {"volume_size", &P::volume_size, SettingGroup::Map, "voxels", 1, 1 << 16, false, 3, "",
     "dense: the box's size (x y z)"},
    {"volume_offset", &P::volume_offset, SettingGroup::Map, "voxels", -(1 << 24), 1 << 24, false, 3, "",
     "dense: the box's first voxel in grid units (x y z)"},
    {"label_update", &P::label_update, SettingGroup::Map, "", 0, 0, false, 0, "probabilistic vote",
     "class update on disagreement: switch with probability 1/(count+1) (probabilistic, the report's rule) or "
     "majority vote (vote: more robust to noisy segmentations)"},
    {"swap", &P::swap, SettingGroup::Map, "", 0, 0, false, 0, "",
     "swapping: only the map near the view stays in the voxel array (active_blocks), the rest goes to host memory "
     "or swap_file",
     CliForm::Flag},
    {"active_blocks", &P::active_blocks, SettingGroup::Map, "", 0, kMostBlocks, false, 0, "",
     "swapping: blocks the active voxel array holds at most (> 0 implies swap; 0 = max_blocks)"},
    {"swap_file", &P::swap_file, SettingGroup::Map, "", 0, 0, false, 0, "",
     "swapping: keep the swapped-out map in this new file (an existing path is refused; deleted as it opens) "
     "instead of memory (implies swap)"},
    {"swap_blocks_per_frame", &P::swap_blocks_per_frame, SettingGroup::Map, "", 1, 1 << 20, false, 0, "",
     "swapping: blocks moved each way per frame at most"},
    {"submaps", &P::submaps, SettingGroup::Map, "", 0, 0, false, 0, "",
     "the map as local submaps with poses in the world, joined by a pose graph (hash index; trajectory.txt then "
     "holds the optimised poses)",
     CliForm::OnOff},
    {"submap_distance", &P::submap_distance, SettingGroup::Map, "m", 0, 1000, true, 0, "",
     "submaps: a new one starts once the camera is this far from the active one's first camera"},
    {"submap_overlap_frames", &P::submap_overlap_frames, SettingGroup::Map, "", 0, 1000, false, 0, "",
     "submaps: frames fused into both the old and the new submap at most before the new one is tracked against (it "
     "is once it covers a frame as well as the old)"},
    {"tracker", &P::tracker, SettingGroup::Tracking, "", 0, 0, false, 0, "icp color ren rgbd",
     "icp | color | ren | rgbd (default: rgbd, robust ICP plus colour aligned to the map's colours and, beyond "
     "max_depth, to keyframes of the far depths; ren: the same without colour)"},
    {"tracker_config", &P::tracker_config, SettingGroup::Tracking, "", 0, 0, false, 0, "",
     "tracker settings file ('key = value' lines), applied before the other tracker settings", CliForm::Value, "",
     existingFileProblem},
    {"tracker_levels", &P::tracker_levels, SettingGroup::Tracking, "", 0, 0, false, 0, "",
     "pyramid levels coarse to fine: r rotation, t translation, b both (e.g. rbb)", CliForm::Value, "", levelsProblem},
    {"tracker_iterations", &P::tracker_iterations, SettingGroup::Tracking, "", 1, 1000, false, 0, "",
     "iterations per level, coarse to fine (one value: every level)"},
    {"tracker_max_distance", &P::tracker_max_distance, SettingGroup::Tracking, "m", 0, 10, true, 0, "",
     "ICP outlier distance per level, coarse to fine (one value: every level)"},
    {"relocalise", &P::relocalise, SettingGroup::Tracking, "", 0, 0, false, 0, "",
     "once tracking is lost, find the camera again from keyframes (nothing is fused until then)", CliForm::OnOff},
    {"relocalise_candidates", &P::relocalise_candidates, SettingGroup::Tracking, "", 1, 1000, false, 0, "",
     "relocalisation: keyframes tried per lost frame, most alike first"},
    {"relocalise_max_speed", &P::relocalise_max_speed, SettingGroup::Tracking, "m/s", 0, 1e6, false, 0, "",
     "relocalisation: how fast the camera may have moved since the last good frame; poses farther away are not "
     "taken (0: no limit)"},
    {"relocalise_min_color_correlation", &P::relocalise_min_color_correlation, SettingGroup::Tracking, "", -1, 1, false,
     0, "",
     "relocalisation: how well a found pose's view must correlate with the map's colours (colour voxels; -1: no "
     "colour test)",
     CliForm::Value, "relocalise_min_colour_correlation"},
};

std::string numberText(double v) {
    std::ostringstream out;
    out << v;
    return out.str();
}

std::string floatText(float v) {
    char text[32];
    const auto end = std::to_chars(text, text + sizeof text, v).ptr;
    return std::string(text, end);
}

std::string rangeText(const SettingRow& row) {
    return (row.min_open ? "(" : "[") + numberText(row.min) + ", " + numberText(row.max) + "]";
}

template <class T>
std::string numberProblem(const SettingRow& row, T v) {
    const double d = double(v);
    const bool in = (row.min_open ? d > row.min : d >= row.min) && d <= row.max;  // NaN is never in
    return in ? std::string() : numberText(d) + " is not in " + rangeText(row);
}

std::string choicesText(const char* choices) {
    std::string text = choices;
    for (std::size_t at = text.find(' '); at != std::string::npos; at = text.find(' ', at + 2))
        text.replace(at, 1, ", ");
    return text;
}

bool isChoice(const std::string& value, const char* choices) {
    std::istringstream words(choices);
    for (std::string word; words >> word;)
        if (word == value) return true;
    return false;
}

}  // namespace

const std::vector<SettingRow>& pipelineSettingRows() { return kRows; }

const SettingRow* findSettingRow(const std::string& name) {
    for (const SettingRow& row : kRows)
        if (name == row.name) return &row;
    return nullptr;
}

std::string optionName(const SettingRow& row) {
    std::string name = std::string("--") + row.name;
    for (char& c : name)
        if (c == '_') c = '-';
    return name;
}

std::string settingProblem(const SettingRow& row, const PipelineSettings& s) {
    return std::visit(
        [&](auto member) -> std::string {
            const auto& value = s.*member;
            using T = std::decay_t<decltype(value)>;
            if constexpr (std::is_same_v<T, bool>) {
                return {};
            } else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, float>) {
                return numberProblem(row, value);
            } else if constexpr (std::is_same_v<T, std::string>) {
                // An empty text that is the default means "not given" (tracker: the settings file's or rgbd).
                if (value.empty() && (PipelineSettings{}.*member).empty()) return {};
                if (*row.choices && !isChoice(value, row.choices))
                    return "'" + value + "' is not one of " + choicesText(row.choices);
                return row.check ? row.check(value) : std::string();
            } else {
                if (row.list_size > 0 && int(value.size()) != row.list_size)
                    return "takes " + std::to_string(row.list_size) + " numbers, not " + std::to_string(value.size());
                for (const auto v : value)
                    if (std::string why = numberProblem(row, v); !why.empty()) return why;
                return {};
            }
        },
        row.member);
}

std::string settingText(const SettingRow& row, const PipelineSettings& s) {
    return std::visit(
        [&](auto member) -> std::string {
            const auto& value = s.*member;
            using T = std::decay_t<decltype(value)>;
            if constexpr (std::is_same_v<T, bool>) {
                return row.cli == CliForm::OnOff ? (value ? "on" : "off") : (value ? "true" : "false");
            } else if constexpr (std::is_same_v<T, int>) {
                return std::to_string(value);
            } else if constexpr (std::is_same_v<T, float>) {
                return floatText(value);
            } else if constexpr (std::is_same_v<T, std::string>) {
                return value;
            } else {
                std::string text;
                for (const auto v : value) {
                    if constexpr (std::is_same_v<decltype(v), const float>)
                        text += (text.empty() ? "" : " ") + floatText(v);
                    else
                        text += (text.empty() ? "" : " ") + std::to_string(v);
                }
                return text;
            }
        },
        row.member);
}

double floatAsDecimal(float v) { return std::stod(floatText(v)); }

std::string settingDescription(const SettingRow& row) {
    std::string text = row.help;
    if (*row.unit) text += " (" + std::string(row.unit) + ")";
    return text;
}

MainEngineSettings PipelineSettings::toEngineSettings() const {
    for (const SettingRow& row : kRows)
        if (std::string why = settingProblem(row, *this); !why.empty())
            throw ConfigError(std::string(row.name) + ": " + why);
    MainEngineSettings s;
    s.voxel_type = parseVoxelType(voxel);
    s.index_type = parseIndexType(index);
    s.device = device == "cuda" ? Device::CUDA : Device::CPU;
    s.scene.voxel_size_m = voxel_size;
    s.scene.mu_m = mu;
    s.scene.max_weight = max_weight;
    s.scene.view_frustum_min_m = min_depth;
    s.scene.view_frustum_max_m = max_depth;
    s.scene.label_update = label_update == "vote" ? LabelUpdate::Vote : LabelUpdate::Probabilistic;
    s.depth_gap_tolerance = depth_gap_tolerance;
    s.hash.max_block_count = active_blocks > 0 ? active_blocks : max_blocks;
    s.hash.bucket_count = hash_buckets;
    s.hash.excess_entry_count = hash_excess;
    s.hash.max_bucket_count = hash_max_buckets;
    s.dense_size = {volume_size[0], volume_size[1], volume_size[2]};
    s.dense_offset = {volume_offset[0], volume_offset[1], volume_offset[2]};
    s.swap.enabled = swap || active_blocks > 0 || !swap_file.empty();
    s.swap.swap_file = swap_file;
    s.swap.blocks_per_frame = swap_blocks_per_frame;
    s.submaps.enabled = submaps;
    s.submaps.max_distance_m = submap_distance;
    s.submaps.overlap_frames = submap_overlap_frames;
    s.tracker = trackerSettingsWith(
        {tracker_config, tracker, tracker_levels, tracker_iterations, tracker_max_distance, "the tracker settings"});
    s.relocalisation.enabled = relocalise;
    s.relocalisation.candidates = relocalise_candidates;
    s.relocalisation.max_speed_m_per_s = relocalise_max_speed;
    s.relocalisation.min_color_correlation = relocalise_min_color_correlation;
    return s;
}

PipelineSettings PipelineSettings::of(const MainEngineSettings& e) {
    PipelineSettings p;
    p.voxel = toString(e.voxel_type);
    p.index = toString(e.index_type);
    p.device = e.device == Device::CUDA ? "cuda" : "cpu";
    p.voxel_size = e.scene.voxel_size_m;
    p.mu = e.scene.mu_m;
    p.max_weight = e.scene.max_weight;
    p.min_depth = e.scene.view_frustum_min_m;
    p.max_depth = e.scene.view_frustum_max_m;
    p.label_update = e.scene.label_update == LabelUpdate::Vote ? "vote" : "probabilistic";
    p.depth_gap_tolerance = e.depth_gap_tolerance;
    p.max_blocks = e.hash.max_block_count;
    p.hash_buckets = e.hash.bucket_count;
    p.hash_excess = e.hash.excess_entry_count;
    p.hash_max_buckets = e.hash.max_bucket_count;
    p.volume_size = {e.dense_size.x, e.dense_size.y, e.dense_size.z};
    p.volume_offset = {e.dense_offset.x, e.dense_offset.y, e.dense_offset.z};
    p.swap = e.swap.enabled;
    p.active_blocks = e.swap.enabled ? e.hash.max_block_count : 0;
    p.swap_file = e.swap.swap_file;
    p.swap_blocks_per_frame = e.swap.blocks_per_frame;
    p.submaps = e.submaps.enabled;
    p.submap_distance = e.submaps.max_distance_m;
    p.submap_overlap_frames = e.submaps.overlap_frames;
    p.tracker = toString(e.tracker.kind);
    p.tracker_levels.clear();
    for (const TrackerLevel& level : e.tracker.levels) {
        p.tracker_levels += char(level.motion);
        p.tracker_iterations.push_back(level.max_iterations);
        p.tracker_max_distance.push_back(level.max_distance_m);
    }
    p.relocalise = e.relocalisation.enabled;
    p.relocalise_candidates = e.relocalisation.candidates;
    p.relocalise_max_speed = e.relocalisation.max_speed_m_per_s;
    p.relocalise_min_color_correlation = e.relocalisation.min_color_correlation;
    return p;
}

void PipelineSettings::adopt(const MapFileInfo& info) {
    voxel = info.voxel_type;
    if (info.submap_count > 0) submaps = true;  // a single map loads either way
    index = info.hash ? "hash" : "dense";
    voxel_size = info.scene.voxel_size_m;
    mu = info.scene.mu_m;
    if (info.hash) {
        max_blocks = info.hash_settings.max_block_count;
        hash_buckets = info.hash_settings.bucket_count;
        hash_excess = info.hash_settings.excess_entry_count;
    } else {
        volume_size = {info.dense_size.x, info.dense_size.y, info.dense_size.z};
        volume_offset = {info.dense_offset.x, info.dense_offset.y, info.dense_offset.z};
    }
}

}  // namespace voxfuse
