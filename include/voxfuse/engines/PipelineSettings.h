#pragma once
// The settings a user gives the pipeline, by the names every front-end shares: `voxfuse --voxel-size`,
// `voxfuse.Settings(voxel_size=...)`, the `settings` block of summary.json. A setting is defined once:
// its member here holds its default, and its row in pipelineSettingRows() (PipelineSettings.cpp) its
// range, unit and help. The command line's options, Python's keywords with their docstrings, their
// checks and the summary are made from the rows; a test holds each front-end to them.

#include <string>
#include <variant>
#include <vector>

#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/io/MapFile.h"

namespace voxfuse {

struct PipelineSettings {
    // The map.
    std::string voxel = "s_rgb";  // colour voxels: the default tracker aligns each frame's colours to the map's
    std::string index = "hash";
    std::string device = "cpu";
    float voxel_size = SceneParams{}.voxel_size_m;
    float mu = SceneParams{}.mu_m;
    int max_weight = SceneParams{}.max_weight;
    float min_depth = SceneParams{}.view_frustum_min_m;
    float max_depth = SceneParams{}.view_frustum_max_m;
    float depth_gap_tolerance = MainEngineSettings{}.depth_gap_tolerance;
    int max_blocks = kAutomaticBlockCount;
    int hash_buckets = engineHashDefaults().bucket_count;
    int hash_excess = engineHashDefaults().excess_entry_count;
    int hash_max_buckets = engineHashDefaults().max_bucket_count;
    std::vector<int> volume_size{512, 512, 512};
    std::vector<int> volume_offset{-256, -256, 0};
    std::string label_update = "probabilistic";
    // Swapping.
    bool swap = false;
    int active_blocks = 0;  // > 0: swapping with an active voxel array of this many blocks
    std::string swap_file;
    int swap_blocks_per_frame = SwapSettings{}.blocks_per_frame;
    // Submaps.
    bool submaps = SubmapSettings{}.enabled;
    float submap_distance = SubmapSettings{}.max_distance_m;
    int submap_overlap_frames = SubmapSettings{}.overlap_frames;
    // The camera: overrides of the tracker's settings (TrackerOverrides), empty = the defaults.
    std::string tracker;
    std::string tracker_config;
    std::string tracker_levels;
    std::vector<int> tracker_iterations;
    std::vector<float> tracker_max_distance;
    // Relocalisation.
    bool relocalise = RelocalisationSettings{}.enabled;
    int relocalise_candidates = RelocalisationSettings{}.candidates;
    float relocalise_max_speed = RelocalisationSettings{}.max_speed_m_per_s;
    float relocalise_min_color_correlation = RelocalisationSettings{}.min_color_correlation;

    // The engine's settings; ConfigError naming the setting when one is out of its row's range or the
    // settings do not work together.
    MainEngineSettings toEngineSettings() const;
    // The settings that make `engine` (the inverse of toEngineSettings, with the tracker's kind, levels,
    // iterations and distances written out; tracker_config stays empty: its values are in them).
    static PipelineSettings of(const MainEngineSettings& engine);
    // These settings with those a map file fixes: voxel type, index and its settings, voxel size, mu,
    // and submaps for a map of submaps.
    void adopt(const MapFileInfo& info);
};

using SettingMember = std::variant<bool PipelineSettings::*, int PipelineSettings::*, float PipelineSettings::*,
                                   std::string PipelineSettings::*, std::vector<int> PipelineSettings::*,
                                   std::vector<float> PipelineSettings::*>;

// How the command line offers a setting: an option with a value, a flag (--swap), or on|off.
enum class CliForm { Value, Flag, OnOff };

enum class SettingGroup { Map, Tracking };  // where `voxfuse --help` lists it

struct SettingRow {
    const char* name;  // Python keyword and summary key; the option is --name with dashes for underscores
    SettingMember member;
    SettingGroup group;
    const char* unit;  // of a number: "m", "m/s", "blocks", ...; "" when it has none
    // Numbers (each one of a list): the accepted range, [min, max], or (min, max] with min_open.
    double min = 0.0, max = 0.0;
    bool min_open = false;
    int list_size = 0;         // lists: the exact number of values, 0 for any
    const char* choices = "";  // text: the accepted values, space-separated ("" = any text)
    const char* help = "";
    CliForm cli = CliForm::Value;
    const char* former_name = "";  // a former spelling, accepted with a warning for a release
    // Text: a check beyond the choices; "" when `value` is fine, else why not.
    std::string (*check)(const std::string& value) = nullptr;
};

const std::vector<SettingRow>& pipelineSettingRows();
const SettingRow* findSettingRow(const std::string& name);  // nullptr when there is none
std::string optionName(const SettingRow& row);              // "--voxel-size"

// Why `settings`' value of `row` is not accepted ("" when it is): out of range, not a choice, a list
// of the wrong length. Without the setting's name (callers say it in their own spelling).
std::string settingProblem(const SettingRow& row, const PipelineSettings& settings);
// The value as text, as the command line writes it ("0.005", "512 512 512", "on").
std::string settingText(const SettingRow& row, const PipelineSettings& settings);
// The double of the shortest decimal that reads back as `v`: 0.005f as 0.005, not 0.004999999888, for
// reports and Python, which hold doubles.
double floatAsDecimal(float v);
// The help with the unit, for --help and docstrings.
std::string settingDescription(const SettingRow& row);

}  // namespace voxfuse
