#include "EngineOptions.h"

#include <algorithm>

#include "OptionChecks.h"
#include "RelocalisationOptions.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/TrackerSettings.h"

namespace voxfuse::app {

bool EngineOptions::wasGiven(const char* option) const {
    return std::find(given.begin(), given.end(), option) != given.end();
}

void addMapOptions(CLI::App& cli, EngineOptions& o) {
    MainEngineSettings& e = o.engine;
    cli.add_option("--voxel-size", e.scene.voxel_size_m, "voxel edge in metres")
        ->capture_default_str()
        ->check(floatIn(0.0, 1.0, true));
    cli.add_option("--mu", e.scene.mu_m, "truncation band in metres")
        ->capture_default_str()
        ->check(floatIn(0.0, 10.0, true));
    cli.add_option("--max-weight", e.scene.max_weight, "cap on the per-voxel weight")
        ->capture_default_str()
        ->check(intIn(1, 255));
    cli.add_option("--min-depth", e.scene.view_frustum_min_m, "ignore depth below (m)")
        ->capture_default_str()
        ->check(floatIn(0.0, 1000.0));
    cli.add_option("--max-depth", e.scene.view_frustum_max_m, "ignore depth beyond (m)")
        ->capture_default_str()
        ->check(floatIn(0.0, 1000.0, true));
    cli.add_option("--depth-gap-tolerance", e.depth_gap_tolerance,
                   "fill a pixel without depth whose two neighbours (left-right, else up-down) agree within this "
                   "fraction of their depth; 0 = never")
        ->capture_default_str()
        ->check(floatIn(0.0, 0.5));
    cli.add_option("--index", o.index, "voxel index")->capture_default_str()->check(CLI::IsMember({"dense", "hash"}));
    cli.add_option("--max-blocks", e.hash.max_block_count,
                   "hash: most 8^3 voxel blocks (memory grows on demand up to this); 0 = automatic: as many as the "
                   "hash has entries "
                   "and 3/4 of the device's free memory holds (on the GPU with room for the copy a growth makes)")
        ->capture_default_str()
        ->check(intIn(0, 1 << 22));
    cli.add_option("--hash-buckets", e.hash.bucket_count, "hash: number of ordered buckets")
        ->capture_default_str()
        ->check(positiveInt());
    cli.add_option("--hash-excess", e.hash.excess_entry_count, "hash: entries in the excess list")
        ->capture_default_str()
        ->check(nonNegativeInt());
    cli.add_option("--volume-size", o.dense_size, "dense volume size in voxels (x y z)")
        ->expected(3)
        ->capture_default_str()
        ->check(intIn(1, 1 << 16));
    cli.add_option("--volume-offset", o.dense_offset, "dense volume's first voxel, grid units (x y z)")
        ->expected(3)
        ->capture_default_str()
        ->check(intIn(-(1 << 24), 1 << 24));
    cli.add_option("--device", o.device,
                   "where the frame loop runs and the map lives: cpu, or cuda for the GPU (image processing, tracking, "
                   "fusion, raycast, meshes)")
        ->capture_default_str()
        ->check(CLI::IsMember({"cpu", "cuda"}));
    cli.add_flag(
        "--swap", e.swap.enabled,
        "swapping: only the map near the view stays in the voxel array (--active-blocks), the rest goes to host memory "
        "or --swap-file");
    cli.add_option("--active-blocks", o.active_blocks,
                   "swapping: blocks the active voxel array holds at most (implies --swap)")
        ->check(intIn(1, 1 << 22));  // the block array's limit, as --max-blocks
    cli.add_option(
        "--swap-file", e.swap.swap_file,
        "swapping: keep the swapped-out map in this new file (an existing path is refused; deleted as it opens) "
        "instead of memory (implies --swap)");
    cli.add_option("--swap-blocks-per-frame", e.swap.blocks_per_frame,
                   "swapping: blocks moved each way per frame at most")
        ->capture_default_str()
        ->check(intIn(1, 1 << 20));
}

void addTrackingOptions(CLI::App& cli, EngineOptions& o) {
    cli.add_option("--poses", o.poses, "track the camera, or take the source's ground truth")
        ->capture_default_str()
        ->check(CLI::IsMember({"track", "groundtruth"}));
    cli.add_option("--tracker", o.tracker,
                   "icp | color | ren | rgbd (default: rgbd, robust ICP plus colour aligned to the map's colours and, "
                   "beyond --max-depth, to keyframes of the far depths; ren: the same without colour)")
        ->check(CLI::IsMember({"icp", "color", "ren", "rgbd"}));
    cli.add_option("--tracker-config", o.tracker_config, "tracker settings file ('key = value' lines)")
        ->check(CLI::ExistingFile);
    cli.add_option("--tracker-levels", o.tracker_levels,
                   "pyramid levels coarse to fine: r rotation, t translation, b both (e.g. rbb)")
        ->check(CLI::Validator(
            [](std::string& levels) -> std::string {
                if (levels.empty() || levels.size() > 8) return "'" + levels + "': need 1 to 8 levels";
                if (levels.find_first_not_of("rtb") != std::string::npos)
                    return "'" + levels + "': level types are r, t or b";
                return {};
            },
            "LEVELS"));
    cli.add_option("--tracker-iterations", o.tracker_iterations, "iterations per level, coarse to fine")
        ->check(intIn(1, 1000));
    cli.add_option("--tracker-max-distance", o.tracker_max_distance,
                   "ICP outlier distance per level (m), coarse to fine")
        ->check(floatIn(0.0, 10.0, true));
    addRelocalisationOptions(cli, o.engine.relocalisation);
}

void noteGivenOptions(const CLI::App& cli, EngineOptions& o) {
    for (const CLI::Option* option : cli.get_options())
        if (option->count() > 0) o.given.push_back(option->get_name());  // "--index", or "source" for the positional
}

void checkEngineOptions(const EngineOptions& o, bool index_from_map) {
    auto refuse = [](const std::string& why) { throw ConfigError(why); };
    const bool dense = o.index == "dense";
    for (const char* option : {"--volume-size", "--volume-offset"})
        if (o.wasGiven(option) && !dense && !index_from_map)
            refuse(std::string(option) + " sets the dense volume: it needs --index dense");
    for (const char* option : {"--max-blocks", "--hash-buckets", "--hash-excess"})
        if (o.wasGiven(option) && dense)
            refuse(std::string(option) + " sets the hash index: it does nothing with --index dense");
    const bool swapping = o.engine.swap.enabled || o.active_blocks > 0 || !o.engine.swap.swap_file.empty();
    if (o.wasGiven("--swap-blocks-per-frame") && !swapping)
        refuse("--swap-blocks-per-frame needs swapping (--swap, --active-blocks or --swap-file)");
    if (swapping && dense) refuse("swapping needs the hash index (--index hash)");
    if (o.poses == "groundtruth")
        for (const char* option :
             {"--tracker", "--tracker-config", "--tracker-levels", "--tracker-iterations", "--tracker-max-distance"})
            if (o.wasGiven(option))
                refuse(std::string(option) + " sets the tracker, which --poses groundtruth does not use");
}

void applyDeviceAndIndex(const EngineOptions& o, MainEngineSettings& s) {
    s.index_type = parseIndexType(o.index);
    if (o.active_blocks > 0 || !s.swap.swap_file.empty()) s.swap.enabled = true;
    if (o.active_blocks > 0) s.hash.max_block_count = o.active_blocks;
    s.device = o.device == "cuda" ? Device::CUDA : Device::CPU;
    s.dense_size = {o.dense_size[0], o.dense_size[1], o.dense_size[2]};
    s.dense_offset = {o.dense_offset[0], o.dense_offset[1], o.dense_offset[2]};
    s.tracker = trackerSettingsWith({o.tracker_config, o.tracker, o.tracker_levels, o.tracker_iterations,
                                     o.tracker_max_distance, "the --tracker options"});
}

}  // namespace voxfuse::app
