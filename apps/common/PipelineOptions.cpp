#include "PipelineOptions.h"

#include <algorithm>
#include <iostream>

#include "DefaultData.h"
#include "OptionChecks.h"
#include "RelocalisationOptions.h"
#include "SyntheticSource.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/TrackerSettings.h"
#include "voxfuse/io/OpenNISource.h"
#include "voxfuse/io/StrayScannerSource.h"
#include "voxfuse/io/UndistortedImageSource.h"

namespace voxfuse::app {

bool PipelineOptions::wasGiven(const char* option) const { return std::find(given.begin(), given.end(), option) != given.end(); }

void addSourceOptions(CLI::App& cli, PipelineOptions& o) {
    cli.add_option("source", o.source,
                   "TUM RGB-D folder, per-frame folder (frame-XXXXXX.depth.png), OpenNI .oni recording, Stray Scanner (iPhone LiDAR) "
                   "folder, or synthetic[:N] / synthetic-corridor[:N] (rendered in memory)");
    cli.add_flag("--live", o.live, "read a live OpenNI2 camera (Kinect, PrimeSense, Structure)");
    cli.add_option("--device-uri", o.device_uri, "with --live: which camera (see --list-devices; default: the first)");
    cli.add_flag("--list-devices", o.list_devices, "list the OpenNI2 cameras and exit");
    cli.add_flag("--threaded", o.threaded, "decode and undistort frames on a reader thread ahead of the engine (always on for --live)");
    cli.add_option("--min-confidence", o.source_options.min_depth_confidence, "iPhone LiDAR: keep depth of at least this confidence (0-2)")
        ->capture_default_str()->check(intIn(0, 2));
    cli.add_option("--rgb", o.source_options.rgb_pattern, "PPM colour file pattern, e.g. frames/%04i.ppm");
    cli.add_option("--depth", o.source_options.depth_pattern, "16-bit PGM depth file pattern, e.g. frames/%04i.pgm");
    cli.add_option("--calib", o.source_options.calib_path, "InfiniTAM calib.txt (overrides the source's own)");
    cli.add_option("--skip", o.skip_frames, "drop the first N frames of the source (e.g. those a --load-map map already holds)")
        ->check(nonNegativeInt());
}

void addMapOptions(CLI::App& cli, PipelineOptions& o) {
    MainEngineSettings& e = o.engine;
    cli.add_option("--voxel-size", e.scene.voxel_size_m, "voxel edge in metres")->capture_default_str()->check(floatIn(0.0, 1.0, true));
    cli.add_option("--mu", e.scene.mu_m, "truncation band in metres")->capture_default_str()->check(floatIn(0.0, 10.0, true));
    cli.add_option("--max-weight", e.scene.max_weight, "cap on the per-voxel weight")->capture_default_str()->check(intIn(1, 255));
    cli.add_option("--min-depth", e.scene.view_frustum_min_m, "ignore depth below (m)")->capture_default_str()->check(floatIn(0.0, 1000.0));
    cli.add_option("--max-depth", e.scene.view_frustum_max_m, "ignore depth beyond (m)")->capture_default_str()->check(floatIn(0.0, 1000.0, true));
    cli.add_option("--depth-gap-tolerance", e.depth_gap_tolerance,
                   "fill a pixel without depth whose two neighbours (left-right, else up-down) agree within this fraction of their depth; 0 = never")
        ->capture_default_str()->check(floatIn(0.0, 0.5));
    addVoxelAndLabelOptions(cli, o.labels, "s_rgb");
    cli.add_option("--index", o.index, "voxel index")->capture_default_str()->check(CLI::IsMember({"dense", "hash"}));
    cli.add_option("--max-blocks", e.hash.max_block_count,
                   "hash: most 8^3 voxel blocks (memory grows on demand up to this); 0 = automatic: as many as the hash has entries "
                   "and 3/4 of the device's free memory holds (on the GPU with room for the copy a growth makes)")
        ->capture_default_str()->check(intIn(0, 1 << 22));
    cli.add_option("--hash-buckets", e.hash.bucket_count, "hash: number of ordered buckets")->capture_default_str()->check(positiveInt());
    cli.add_option("--hash-excess", e.hash.excess_entry_count, "hash: entries in the excess list")->capture_default_str()->check(nonNegativeInt());
    cli.add_option("--volume-size", o.dense_size, "dense volume size in voxels (x y z)")->expected(3)->capture_default_str()->check(intIn(1, 1 << 16));
    cli.add_option("--volume-offset", o.dense_offset, "dense volume's first voxel, grid units (x y z)")
        ->expected(3)->capture_default_str()->check(intIn(-(1 << 24), 1 << 24));
    cli.add_option("--device", o.device,
                   "where the frame loop runs and the map lives: cpu, or cuda for the GPU (image processing, tracking, fusion, raycast, meshes)")
        ->capture_default_str()->check(CLI::IsMember({"cpu", "cuda"}));
    cli.add_flag("--swap", e.swap.enabled,
                 "swapping: only the map near the view stays in the voxel array (--active-blocks), the rest goes to host memory "
                 "or --swap-file");
    cli.add_option("--active-blocks", o.active_blocks, "swapping: blocks the active voxel array holds at most (implies --swap)")
        ->check(positiveInt());
    cli.add_option("--swap-file", e.swap.swap_file,
                   "swapping: keep the swapped-out map in this new file (an existing path is refused; deleted as it opens) "
                   "instead of memory (implies --swap)");
    cli.add_option("--swap-blocks-per-frame", e.swap.blocks_per_frame, "swapping: blocks moved each way per frame at most")
        ->capture_default_str()->check(intIn(1, 1 << 20));
}

void addTrackingOptions(CLI::App& cli, PipelineOptions& o) {
    cli.add_option("--poses", o.poses, "track the camera, or take the source's ground truth")
        ->capture_default_str()->check(CLI::IsMember({"track", "groundtruth"}));
    cli.add_option("--tracker", o.tracker, "icp | color | ren | rgbd (default: ren, ICP then a robust refinement)")
        ->check(CLI::IsMember({"icp", "color", "ren", "rgbd"}));
    cli.add_option("--tracker-config", o.tracker_config, "tracker settings file ('key = value' lines)")->check(CLI::ExistingFile);
    cli.add_option("--tracker-levels", o.tracker_levels, "pyramid levels coarse to fine: r rotation, t translation, b both (e.g. rbb)")
        ->check(CLI::Validator(
            [](std::string& levels) -> std::string {
                if (levels.empty() || levels.size() > 8) return "'" + levels + "': need 1 to 8 levels";
                if (levels.find_first_not_of("rtb") != std::string::npos) return "'" + levels + "': level types are r, t or b";
                return {};
            },
            "LEVELS"));
    cli.add_option("--tracker-iterations", o.tracker_iterations, "iterations per level, coarse to fine")->check(intIn(1, 1000));
    cli.add_option("--tracker-max-distance", o.tracker_max_distance, "ICP outlier distance per level (m), coarse to fine")
        ->check(floatIn(0.0, 10.0, true));
    addRelocalisationOptions(cli, o.engine.relocalisation);
}

void noteGivenOptions(const CLI::App& cli, PipelineOptions& o) {
    for (const CLI::Option* option : cli.get_options())
        if (option->count() > 0) o.given.push_back(option->get_name());  // "--index", or "source" for the positional
}

void checkPipelineOptions(const PipelineOptions& o) {
    auto refuse = [](const std::string& why) { throw ConfigError(why); };
    const bool dense = o.index == "dense";
    for (const char* option : {"--volume-size", "--volume-offset"})
        if (o.wasGiven(option) && !dense && o.load_map.empty()) refuse(std::string(option) + " sets the dense volume: it needs --index dense");
    for (const char* option : {"--max-blocks", "--hash-buckets", "--hash-excess"})
        if (o.wasGiven(option) && dense) refuse(std::string(option) + " sets the hash index: it does nothing with --index dense");
    const bool swapping = o.engine.swap.enabled || o.active_blocks > 0 || !o.engine.swap.swap_file.empty();
    if (o.wasGiven("--swap-blocks-per-frame") && !swapping) refuse("--swap-blocks-per-frame needs swapping (--swap, --active-blocks or --swap-file)");
    if (swapping && dense) refuse("swapping needs the hash index (--index hash)");
    if (o.poses == "groundtruth")
        for (const char* option : {"--tracker", "--tracker-config", "--tracker-levels", "--tracker-iterations", "--tracker-max-distance"})
            if (o.wasGiven(option)) refuse(std::string(option) + " sets the tracker, which --poses groundtruth does not use");
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
    MainEngineSettings adopted = settingsForMap(map, o.engine);
    if (o.wasGiven("--max-blocks")) adopted.hash.max_block_count = o.engine.hash.max_block_count;
    auto conflict = [&](const char* option, const std::string& what) {
        throw ConfigError(o.load_map + ": the map has " + what + "; " + option + " cannot change it (leave the option out)");
    };
    if (!o.labels.voxel.empty() && o.labels.voxel != map.voxel_type) conflict("--voxel", "'" + map.voxel_type + "' voxels");
    if (o.wasGiven("--index") && o.index != (map.hash ? "hash" : "dense")) conflict("--index", std::string("the ") + (map.hash ? "hash" : "dense") + " index");
    if (o.wasGiven("--voxel-size") && o.engine.scene.voxel_size_m != map.scene.voxel_size_m)
        conflict("--voxel-size", std::to_string(map.scene.voxel_size_m) + " m voxels");
    if (o.wasGiven("--mu") && o.engine.scene.mu_m != map.scene.mu_m) conflict("--mu", "mu " + std::to_string(map.scene.mu_m) + " m");
    if (o.wasGiven("--max-blocks") && !map.hash) conflict("--max-blocks", "the dense index");
    for (const char* option : {"--hash-buckets", "--hash-excess", "--volume-size", "--volume-offset"})
        if (o.wasGiven(option)) conflict(option, "its own index settings");
    o.labels.voxel = map.voxel_type;
    o.index = map.hash ? "hash" : "dense";
    o.engine = adopted;
    o.dense_size = {adopted.dense_size.x, adopted.dense_size.y, adopted.dense_size.z};
    o.dense_offset = {adopted.dense_offset.x, adopted.dense_offset.y, adopted.dense_offset.z};
}

void applyDeviceAndIndex(const PipelineOptions& o, MainEngineSettings& s) {
    s.index_type = parseIndexType(o.index);
    if (o.active_blocks > 0 || !s.swap.swap_file.empty()) s.swap.enabled = true;
    if (o.active_blocks > 0) s.hash.max_block_count = o.active_blocks;
    s.device = o.device == "cuda" ? Device::CUDA : Device::CPU;
    s.dense_size = {o.dense_size[0], o.dense_size[1], o.dense_size[2]};
    s.dense_offset = {o.dense_offset[0], o.dense_offset[1], o.dense_offset[2]};
    s.tracker = trackerSettingsWith({o.tracker_config, o.tracker, o.tracker_levels, o.tracker_iterations, o.tracker_max_distance, "the --tracker options"});
}

void listCameras() {
    const std::vector<std::string> uris = OpenNISource::deviceUris();
    std::cout << (uris.empty() ? "no OpenNI2 camera found\n" : "OpenNI2 cameras:\n");
    for (const auto& uri : uris) std::cout << "  " << uri << "\n";
}

namespace {

std::unique_ptr<ImageSource> openSource(PipelineOptions& o, const char* program) {
    if (o.live) return OpenNISource::openDevice(o.device_uri, o.source_options);
    if (o.source.empty() && o.source_options.rgb_pattern.empty() && o.source_options.depth_pattern.empty()) o.source = bundledSequence(program);
    if (SyntheticSource::isSyntheticName(o.source)) return SyntheticSource::open(o.source);
    return openImageSource(o.source, o.source_options);
}

}  // namespace

Pipeline openPipeline(PipelineOptions& o, const char* program) {
    Pipeline p;
    p.source = openSource(o, program);
    // Label images are decoded on the reader thread too: the stream goes inside it.
    p.labels = attachLabelInput(p.source, o.source, o.labels, o.engine, program);
    p.source = framesForEngine(std::move(p.source), o.threaded);
    std::cerr << program << ": " << p.source->description() << "\n";
    applyDeviceAndIndex(o, o.engine);
    p.engine = MainEngine::create(o.engine, p.source->calib());
    if (!o.load_map.empty()) p.engine->loadMap(o.load_map);
    return p;
}

}  // namespace voxfuse::app
