#pragma once
// What reads the frames, how the map is built and how the camera is tracked: the options voxfuse and
// voxfuse_viewer share, defined once with their checks, and what they make (the source, the engine
// settings). The viewer is the demo people run on a camera, so it takes everything voxfuse takes
// that shapes the reconstruction; only the outputs differ.

#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "LabelInput.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/io/ImageSource.h"
#include "voxfuse/io/MapFile.h"

namespace voxfuse::app {

struct PipelineOptions {
    // Where the frames come from.
    std::string source;  // SOURCE: a recording, synthetic[:N] / synthetic-corridor[:N]; "" = the bundled sequence
    SourceOptions source_options;
    bool live = false;              // an OpenNI2 camera instead of a recording
    std::string device_uri;         // which camera ("" = the first)
    bool list_devices = false;
    bool threaded = false;          // decode (and undistort) on a reader thread ahead of the engine
    int skip_frames = 0;            // dropped from the start of the source
    // The map.
    std::string index = "hash";
    std::string device = "cpu";
    int active_blocks = 0;          // > 0: swapping with an active voxel array of this many blocks
    LabelInputOptions labels;       // and --voxel
    std::vector<int> dense_size{512, 512, 512};
    std::vector<int> dense_offset{-256, -256, 0};
    std::string load_map;           // continue this map (its voxel type, index and voxel size); each program adds --load-map
    // The camera.
    std::string poses = "track";
    std::string tracker;            // overrides of the tracker settings, applied in this order:
    std::string tracker_config;     //   the settings file, then the single options
    std::string tracker_levels;
    std::vector<int> tracker_iterations;
    std::vector<float> tracker_max_distance;

    MainEngineSettings engine;
    std::vector<std::string> given;  // options given on the command line, by their long names ("source" for SOURCE)
    bool wasGiven(const char* option) const;
};

// SOURCE, --live, --device-uri, --list-devices, --threaded, --min-confidence, --rgb, --depth, --calib, --skip.
void addSourceOptions(CLI::App& cli, PipelineOptions& o);
// --voxel-size, --mu, --max-weight, --min-depth, --max-depth, --depth-gap-tolerance, the voxel and label
// options, --index, --max-blocks, --hash-buckets, --hash-excess, --volume-size, --volume-offset, --device
// and the swapping options.
void addMapOptions(CLI::App& cli, PipelineOptions& o);
// --poses, the tracker options and the relocalisation options.
void addTrackingOptions(CLI::App& cli, PipelineOptions& o);
// After parsing: which options the command line gave (checks and --load-map need to know).
void noteGivenOptions(const CLI::App& cli, PipelineOptions& o);

// Options that would be silently ignored in this combination are errors instead (ConfigError).
void checkPipelineOptions(const PipelineOptions& o);
// With --load-map the map decides the voxel type, the index and its table, the voxel size and mu;
// another one given on the command line is a ConfigError. The block ceiling is the map's unless
// --max-blocks gives one: a map that filled its ceiling elsewhere must be able to go on.
void adoptMapSettings(PipelineOptions& o, const MapFileInfo& map);
// The engine settings the options make, beside those the options write directly (index, device,
// swapping, dense volume, tracker). The voxel type is attachLabelInput's.
void applyDeviceAndIndex(const PipelineOptions& o, MainEngineSettings& s);

// --list-devices: prints the OpenNI2 cameras on stdout.
void listCameras();

// What the options make, the same in every program that takes them.
struct Pipeline {
    std::unique_ptr<ImageSource> source;    // the frames as the engine takes them
    LabelledImageSource* labels = nullptr;  // the label stream inside `source`, if any
    std::unique_ptr<MainEngine> engine;     // with the --load-map map loaded
};
// Opens the source the options name (a live camera, a synthetic sequence, a recording, or the bundled
// sequence when nothing is named) with its labels, undistorted and read ahead with --threaded (always
// for a camera, so that the engine never makes the driver wait), says it on stderr, settles the
// voxel type and the engine settings in o.engine and makes the engine. After adoptMapSettings.
Pipeline openPipeline(PipelineOptions& o, const char* program);

}  // namespace voxfuse::app
