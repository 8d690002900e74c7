#pragma once
// What reads the frames, how the map is built and how the camera is tracked: the options voxfuse and
// voxfuse_viewer share, defined once with their checks, and what they make (the source, the engine
// settings). The viewer is the demo people run on a camera, so it takes everything voxfuse takes
// that shapes the reconstruction; only the outputs differ. The map and tracking options are
// EngineOptions, which voxfuse_bench takes as well.

#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "EngineOptions.h"
#include "LabelInput.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/io/ImageSource.h"
#include "voxfuse/io/MapFile.h"

namespace voxfuse::app {

struct PipelineOptions : EngineOptions {
    // Where the frames come from.
    std::string source;  // SOURCE: a recording, synthetic[:N] / synthetic-corridor[:N]; "" = the bundled sequence
    SourceOptions source_options;
    bool live = false;       // an OpenNI2 camera instead of a recording
    std::string device_uri;  // which camera ("" = the first)
    bool list_devices = false;
    bool threaded = false;  // decode (and undistort) on a reader thread ahead of the engine
    int skip_frames = 0;    // dropped from the start of the source
    // The map, beside EngineOptions.
    LabelInputOptions labels;
    std::string load_map;  // continue this map (its voxel type, index and voxel size); each program adds --load-map
    MapFileInfo map;       // its header, read by adoptMapSettings
};

// SOURCE, --live, --device-uri, --list-devices, --threaded, --min-confidence, --rgb, --depth, --calib, --skip.
void addSourceOptions(CLI::App& cli, PipelineOptions& o);
// The engine's map options (EngineOptions.h), then the label options.
void addMapOptions(CLI::App& cli, PipelineOptions& o);

// Options that would be silently ignored in this combination are errors instead (ConfigError):
// checkEngineOptions' and the source's.
void checkPipelineOptions(const PipelineOptions& o);
// With --load-map the map decides the voxel type, the index and its table, the voxel size and mu;
// another one given on the command line is a ConfigError. The block ceiling is the map's unless
// --max-blocks gives one: a map that filled its ceiling elsewhere must be able to go on.
void adoptMapSettings(PipelineOptions& o, const MapFileInfo& map);
// --list-devices: prints the OpenNI2 cameras on stdout.
void listCameras();

// The engine's settings the options make: o.settings, with a loaded map's index settings as the map has
// them (also those no option sets, such as a library user's entries per bucket).
MainEngineSettings engineSettings(const PipelineOptions& o);

// What the options make, the same in every program that takes them.
struct Pipeline {
    std::unique_ptr<ImageSource> source;    // the frames as the engine takes them
    LabelledImageSource* labels = nullptr;  // the label stream inside `source`, if any
    std::unique_ptr<MainEngine> engine;     // with the --load-map map loaded
};
// Opens the source the options name (a live camera, a synthetic sequence, a recording, or the bundled
// sequence when nothing is named) with its labels, undistorted and read ahead with --threaded (always
// for a camera, so that the engine never makes the driver wait), says it on stderr, settles the
// voxel type in o.settings and makes the engine. After adoptMapSettings.
Pipeline openPipeline(PipelineOptions& o, const char* program);

}  // namespace voxfuse::app
