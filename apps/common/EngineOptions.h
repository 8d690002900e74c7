#pragma once
// How the map is built and how the camera is tracked: the options every program that runs the engine
// takes (voxfuse, voxfuse_viewer, voxfuse_bench), defined once with their checks. They need no image
// I/O, so the GPU bundle's voxfuse_bench (built without it) takes the same ones. The voxel type is
// not among them: with image I/O it comes with the label options (LabelInput.h).

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "voxfuse/engines/MainEngine.h"

namespace voxfuse::app {

struct EngineOptions {
    // The map.
    std::string index = "hash";
    std::string device = "cpu";
    int active_blocks = 0;  // > 0: swapping with an active voxel array of this many blocks
    std::vector<int> dense_size{512, 512, 512};
    std::vector<int> dense_offset{-256, -256, 0};
    // The camera.
    std::string poses = "track";
    std::string tracker;         // overrides of the tracker settings, applied in this order:
    std::string tracker_config;  //   the settings file, then the single options
    std::string tracker_levels;
    std::vector<int> tracker_iterations;
    std::vector<float> tracker_max_distance;

    MainEngineSettings engine;
    std::vector<std::string> given;  // options given on the command line, by their long names ("source" for SOURCE)
    bool wasGiven(const char* option) const;
};

// --voxel-size, --mu, --max-weight, --min-depth, --max-depth, --depth-gap-tolerance, --index,
// --max-blocks, --hash-buckets, --hash-excess, --volume-size, --volume-offset, --device and the
// swapping options.
void addMapOptions(CLI::App& cli, EngineOptions& o);
// --poses, the tracker options and the relocalisation options.
void addTrackingOptions(CLI::App& cli, EngineOptions& o);
// After parsing: which options the command line gave (checks and --load-map need to know).
void noteGivenOptions(const CLI::App& cli, EngineOptions& o);
// Map and tracking options that would be silently ignored in this combination are errors instead
// (ConfigError). With `index_from_map` (a map file decides the index) the dense volume's options are
// left to the map's own checks.
void checkEngineOptions(const EngineOptions& o, bool index_from_map = false);
// The engine settings the options make, beside those the options write directly: the index, the
// device, swapping, the dense volume and the tracker. The voxel type is the caller's.
void applyDeviceAndIndex(const EngineOptions& o, MainEngineSettings& s);

}  // namespace voxfuse::app
