#pragma once
// How the map is built and how the camera is tracked: the options every program that runs the engine
// takes (voxfuse, voxfuse_viewer, voxfuse_bench), made from the settings table (engines/
// PipelineSettings.h) so that they are Python's settings by the same names, defaults and checks. They
// need no image I/O, so the GPU bundle's voxfuse_bench (built without it) takes the same ones.

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "voxfuse/engines/PipelineSettings.h"

namespace voxfuse::app {

struct EngineOptions {
    PipelineSettings settings;       // one option per row of the table
    std::string poses = "track";     // or "groundtruth": the source's poses, no tracker
    std::vector<std::string> given;  // options given on the command line, by their long names ("source" for SOURCE)
    bool wasGiven(const char* option) const;
};

// One option per setting of `group`, bound to o.settings, with the row's default, range and help.
void addSettingOptions(CLI::App& cli, PipelineSettings& settings, SettingGroup group);
// The map's settings (voxel type, index, voxel size, depth range, swapping, ...).
void addMapOptions(CLI::App& cli, EngineOptions& o);
// --poses and the tracking and relocalisation settings.
void addTrackingOptions(CLI::App& cli, EngineOptions& o);
// After parsing: which options the command line gave (checks and --load-map need to know).
void noteGivenOptions(const CLI::App& cli, EngineOptions& o);
// Map and tracking options that would be silently ignored in this combination are errors instead
// (ConfigError). With `index_from_map` (a map file decides the index) the dense volume's options are
// left to the map's own checks.
void checkEngineOptions(const EngineOptions& o, bool index_from_map = false);

}  // namespace voxfuse::app
