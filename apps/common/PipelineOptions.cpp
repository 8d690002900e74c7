#include "PipelineOptions.h"

#include <algorithm>
#include <iostream>

#include "DefaultData.h"
#include "OptionChecks.h"
#include "SyntheticSource.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/OpenNISource.h"
#include "voxfuse/io/StrayScannerSource.h"
#include "voxfuse/io/UndistortedImageSource.h"

namespace voxfuse::app {

void addSourceOptions(CLI::App& cli, PipelineOptions& o) {
    cli.add_option("source", o.source,
                   "TUM RGB-D folder, per-frame folder (frame-XXXXXX.depth.png), OpenNI .oni recording, Stray Scanner "
                   "(iPhone LiDAR) "
                   "folder, or synthetic[:N] / synthetic-corridor[:N] (rendered in memory)");
    cli.add_flag("--live", o.live, "read a live OpenNI2 camera (Kinect, PrimeSense, Structure)");
    cli.add_option("--device-uri", o.device_uri, "with --live: which camera (see --list-devices; default: the first)");
    cli.add_flag("--list-devices", o.list_devices, "list the OpenNI2 cameras and exit");
    cli.add_flag("--threaded", o.threaded,
                 "decode and undistort frames on a reader thread ahead of the engine (always on for --live)");
    cli.add_option("--min-confidence", o.source_options.min_depth_confidence,
                   "iPhone LiDAR: keep depth of at least this confidence (0-2)")
        ->capture_default_str()
        ->check(intIn(0, 2));
    cli.add_option("--rgb", o.source_options.rgb_pattern, "PPM colour file pattern, e.g. frames/%04i.ppm");
    cli.add_option("--depth", o.source_options.depth_pattern, "16-bit PGM depth file pattern, e.g. frames/%04i.pgm");
    cli.add_option("--calib", o.source_options.calib_path, "InfiniTAM calib.txt (overrides the source's own)");
    cli.add_option("--skip", o.skip_frames,
                   "drop the first N frames of the source (e.g. those a --load-map map already holds)")
        ->check(nonNegativeInt());
}

void addMapOptions(CLI::App& cli, PipelineOptions& o) {
    addMapOptions(cli, static_cast<EngineOptions&>(o));
    addLabelOptions(cli, o.labels);
}

void checkPipelineOptions(const PipelineOptions& o) {
    auto refuse = [](const std::string& why) { throw ConfigError(why); };
    checkEngineOptions(o, !o.load_map.empty());
    if (!o.device_uri.empty() && !o.live) refuse("--device-uri picks a live camera: it needs --live");
    if (o.live && (!o.source.empty() || !o.source_options.depth_pattern.empty()))
        refuse("--live reads a camera: give no SOURCE, --rgb or --depth with it");
    if (!o.source.empty() && !o.source_options.depth_pattern.empty() && SyntheticSource::isSyntheticName(o.source))
        refuse("--rgb/--depth name files: they cannot be used with a synthetic source");
    if (o.wasGiven("--min-confidence") && !StrayScannerSource::isCapture(o.source))
        refuse("--min-confidence filters iPhone LiDAR depth: '" + o.source + "' is not a Stray Scanner capture");
    if (o.wasGiven("--calib") && SyntheticSource::isSyntheticName(o.source))
        refuse("--calib replaces a recording's calibration: the synthetic source renders with its own");
}

void adoptMapSettings(PipelineOptions& o, const MapFileInfo& map) {
    PipelineSettings& s = o.settings;
    auto conflict = [&](const char* option, const std::string& what) {
        throw ConfigError(o.load_map + ": the map has " + what + "; " + option +
                          " cannot change it (leave the option out)");
    };
    if (o.wasGiven("--voxel") && s.voxel != map.voxel_type) conflict("--voxel", "'" + map.voxel_type + "' voxels");
    if (o.wasGiven("--index") && s.index != (map.hash ? "hash" : "dense"))
        conflict("--index", std::string("the ") + (map.hash ? "hash" : "dense") + " index");
    if (o.wasGiven("--voxel-size") && s.voxel_size != map.scene.voxel_size_m)
        conflict("--voxel-size", std::to_string(map.scene.voxel_size_m) + " m voxels");
    if (o.wasGiven("--mu") && s.mu != map.scene.mu_m) conflict("--mu", "mu " + std::to_string(map.scene.mu_m) + " m");
    if (o.wasGiven("--max-blocks") && !map.hash) conflict("--max-blocks", "the dense index");
    for (const char* option : {"--hash-buckets", "--hash-excess", "--volume-size", "--volume-offset"})
        if (o.wasGiven(option)) conflict(option, "its own index settings");
    if (o.wasGiven("--submaps") && !s.submaps && map.submap_count > 0)
        conflict("--submaps", std::to_string(map.submap_count) + " submaps");
    const int max_blocks = s.max_blocks;
    o.map = map;
    s.adopt(map);
    if (o.wasGiven("--max-blocks")) s.max_blocks = max_blocks;
}

MainEngineSettings engineSettings(const PipelineOptions& o) {
    MainEngineSettings s = o.settings.toEngineSettings();
    if (o.load_map.empty()) return s;
    const int max_blocks = s.hash.max_block_count;  // the map's, unless --max-blocks gave one (adoptMapSettings)
    s = settingsForMap(o.map, s);
    s.hash.max_block_count = max_blocks;
    return s;
}

void listCameras() {
    const std::vector<std::string> uris = OpenNISource::deviceUris();
    std::cout << (uris.empty() ? "no OpenNI2 camera found\n" : "OpenNI2 cameras:\n");
    for (const auto& uri : uris) std::cout << "  " << uri << "\n";
}

namespace {

std::unique_ptr<ImageSource> openSource(PipelineOptions& o, const char* program) {
    if (o.live) return OpenNISource::openDevice(o.device_uri, o.source_options);
    if (o.source.empty() && o.source_options.rgb_pattern.empty() && o.source_options.depth_pattern.empty())
        o.source = bundledSequence(program);
    if (SyntheticSource::isSyntheticName(o.source)) return SyntheticSource::open(o.source);
    return openImageSource(o.source, o.source_options);
}

}  // namespace

Pipeline openPipeline(PipelineOptions& o, const char* program) {
    Pipeline p;
    p.source = openSource(o, program);
    // Label images are decoded on the reader thread too: the stream goes inside it.
    // A loaded map's voxel type is as good as given: --labels must not turn it into another.
    const bool voxel_given = o.wasGiven("--voxel") || !o.load_map.empty();
    p.labels = attachLabelInput(p.source, o.source, o.labels, o.settings, voxel_given, program);
    p.source = framesForEngine(std::move(p.source), o.threaded);
    std::cerr << program << ": " << p.source->description() << "\n";
    p.engine = MainEngine::create(engineSettings(o), p.source->calib());
    if (!o.load_map.empty()) p.engine->loadMap(o.load_map);
    return p;
}

}  // namespace voxfuse::app
