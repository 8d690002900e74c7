// voxfuse: the headless command-line front-end. Reads a recorded sequence, fuses it into a TSDF
// volume, and writes the trajectory, per-stage timings, a summary and rendered images.

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "Interrupt.h"
#include "LabelInput.h"
#include "RelocalisationOptions.h"
#include "OptionChecks.h"
#include "OutputFolder.h"
#include "HeapPolicy.h"
#include "CommandLine.h"
#include "DefaultData.h"
#include "ProgramMain.h"
#include "ResourceUsage.h"
#include "RunRecord.h"
#include "SequenceRunner.h"
#include "SyntheticSource.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/core/Timer.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/eval/TrajectoryError.h"
#include "voxfuse/engines/MeshLabels.h"
#include "voxfuse/engines/PointCloudDownsampling.h"
#include "voxfuse/io/AtomicFile.h"
#include "voxfuse/io/ImageIO.h"
#include "voxfuse/io/MapFile.h"
#include "voxfuse/io/MeshIO.h"
#include "voxfuse/io/ImageSource.h"
#include "voxfuse/io/OpenNISource.h"
#include "voxfuse/io/StrayScannerSource.h"
#include "voxfuse/io/ThreadedImageSource.h"
#include "voxfuse/io/UndistortedImageSource.h"
#include "voxfuse/mapping/OccupancyMapper.h"


namespace fs = std::filesystem;
using namespace voxfuse;

namespace {

struct CliOptions {
    std::string source;
    SourceOptions source_options;
    std::string out_dir = "voxfuse_out";
    bool overwrite = false;               // replace an earlier run's outputs in out_dir
    int max_frames = -1;  // -1 = all; 0 = none (with --load-map: the map's outputs only)
    int skip_frames = 0;  // dropped from the start of the source
    int active_blocks = 0;  // > 0: swapping with an active voxel array of this many blocks
    int render_every = 25;
    std::string index = "hash";
    std::string device = "cpu";
    std::string poses = "track";
    bool threaded = false;                // decode (and undistort) on a reader thread ahead of the engine
    bool live = false;                    // read an OpenNI2 camera instead of a recording
    std::string device_uri;               // which camera ("" = the first)
    bool list_devices = false;
    bool write_mesh = false;              // DIR/mesh.ply at the end
    std::string mesh_path;                // or this file (.ply, .obj, .stl)
    bool write_cloud = false;             // DIR/cloud.ply at the end
    float cloud_voxel_m = 0.f;            // downsample the cloud to one point per cell of this size
    float occupancy_res_m = 0.f;          // > 0: an OctoMap with cells of this size -> DIR/occupancy.bt
    app::LabelInputOptions labels;        // and --voxel
    bool mesh_per_class = false;          // DIR/mesh_class_<id>.ply for each class of the mesh
    std::vector<int> exclude_classes;     // dropped from the mesh and the cloud (e.g. people from a static map)
    std::string tracker;                  // overrides of the tracker settings, applied in this order:
    std::string tracker_config;           //   the settings file, then the single options
    std::string tracker_levels;
    std::vector<int> tracker_iterations;
    std::vector<float> tracker_max_distance;
    std::vector<int> dense_size{512, 512, 512};
    std::vector<int> dense_offset{-256, -256, 0};
    std::string save_map;                 // write the map here at the end
    std::string load_map;                 // continue this map (its voxel type, index and voxel size)
    std::vector<std::string> given;       // options given on the command line, by their long names
    MainEngineSettings engine;
};

class ProgressLine {
public:
    explicit ProgressLine(int total) : total_(total), tty_(isatty(STDERR_FILENO)) {}
    void update(int done, double fps) {
        if (!tty_) return;
        if (total_ > 0) std::fprintf(stderr, "\r  frame %d/%d  %.1f fps   ", done, total_, fps);
        else std::fprintf(stderr, "\r  frame %d  %.1f fps   ", done, fps);
        std::fflush(stderr);
    }
    void finish() {
        if (tty_) std::fprintf(stderr, "\n");
    }

private:
    int total_;
    bool tty_;
};

// The tracker settings: defaults, then --tracker-config FILE, then the single options.
TrackerSettings trackerSettings(const CliOptions& o) {
    return trackerSettingsWith({o.tracker_config, o.tracker, o.tracker_levels, o.tracker_iterations, o.tracker_max_distance, "the --tracker options"});
}

std::vector<ClassId> excludedClasses(const CliOptions& o) { return std::vector<ClassId>(o.exclude_classes.begin(), o.exclude_classes.end()); }

void writeMapOutputs(MainEngine& engine, const CliOptions& o, app::OutputFolder& out) {
    if (o.write_mesh || !o.mesh_path.empty() || o.mesh_per_class) {
        const Timer t;
        Mesh mesh;
        engine.extractMesh(mesh);
        if (!o.exclude_classes.empty()) mesh = selectClasses(mesh, excludedClasses(o), ClassSelection::Exclude);
        if (o.write_mesh || !o.mesh_path.empty()) {
            const std::string path = o.mesh_path.empty() ? out.file("mesh.ply") : o.mesh_path;
            writeMesh(path, mesh);
            std::cerr << "voxfuse: mesh " << mesh.vertices.size() << " vertices, " << mesh.triangles.size() << " triangles in "
                      << int(t.elapsedMs()) << " ms -> " << path << "\n";
        }
        if (o.mesh_per_class) {
            for (const ClassMesh& part : splitByClass(mesh)) {
                const bool unlabelled = part.label == kNoLabel;
                const std::string part_path = out.file(unlabelled ? "mesh_unlabelled.ply" : "mesh_class_" + std::to_string(part.label) + ".ply");
                writeMesh(part_path, part.mesh);
                std::cerr << "voxfuse: class " << (unlabelled ? std::string("none") : std::to_string(part.label)) << ": "
                          << part.mesh.triangles.size() << " triangles -> " << part_path << "\n";
            }
        }
    }
    if (o.write_cloud || o.cloud_voxel_m > 0.f) {
        const std::string path = out.file("cloud.ply");
        PointCloud cloud;
        engine.extractPointCloud(cloud);
        if (!o.exclude_classes.empty()) cloud = selectClasses(cloud, excludedClasses(o), ClassSelection::Exclude);
        const std::size_t surface_points = cloud.points.size();
        if (o.cloud_voxel_m > 0.f) cloud = downsampleVoxelGrid(cloud, o.cloud_voxel_m);
        writePointCloudPly(path, cloud);
        std::cerr << "voxfuse: point cloud " << cloud.points.size() << " points (of " << surface_points << " surface points) -> " << path << "\n";
    }
}

// render_<name>.png, and render_class_<name>.png for voxel types with classes.
void saveRenders(MainEngine& engine, app::OutputFolder& out, const std::string& name) {
    const VoxelType type = engine.settings().voxel_type;
    Image<Vec4u8> image;
    engine.renderLast(voxelTypeHasColor(type) ? RenderMode::Color : RenderMode::Shaded, image);
    writePNG(out.file("render_" + name + ".png"), image);
    if (!voxelTypeHasLabels(type)) return;
    engine.renderLast(RenderMode::Class, image);
    writePNG(out.file("render_class_" + name + ".png"), image);
}
void saveRenders(MainEngine& engine, app::OutputFolder& out, int frame_index) {
    char name[16];
    std::snprintf(name, sizeof name, "%06d", frame_index);
    saveRenders(engine, out, std::string(name));
}

// The summary comes last: a folder with a summary.json holds a finished (or cleanly interrupted) run.
void writeRunFiles(app::RunRecord& record, app::OutputFolder& out, bool with_timings) {
    if (with_timings) app::writeTimingsJson(out.file("timings.json"), record);
    out.file("summary.json");
    record.outputs = out.written();
    app::writeSummaryJson(out.file("summary.json"), record);
}

bool given(const CliOptions& o, const char* option) { return std::find(o.given.begin(), o.given.end(), option) != o.given.end(); }

// Options that would be silently ignored in this combination are errors instead.
void checkCombinations(const CliOptions& o) {
    auto refuse = [](const std::string& why) { throw ConfigError(why); };
    const bool dense = o.index == "dense";
    for (const char* option : {"--volume-size", "--volume-offset"})
        if (given(o, option) && !dense && o.load_map.empty()) refuse(std::string(option) + " sets the dense volume: it needs --index dense");
    for (const char* option : {"--max-blocks", "--hash-buckets", "--hash-excess"})
        if (given(o, option) && dense) refuse(std::string(option) + " sets the hash index: it does nothing with --index dense");
    const bool swapping = o.engine.swap.enabled || o.active_blocks > 0 || !o.engine.swap.swap_file.empty();
    if (given(o, "--swap-blocks-per-frame") && !swapping) refuse("--swap-blocks-per-frame needs swapping (--swap, --active-blocks or --swap-file)");
    if (swapping && dense) refuse("swapping needs the hash index (--index hash)");
    if (o.poses == "groundtruth")
        for (const char* option : {"--tracker", "--tracker-config", "--tracker-levels", "--tracker-iterations", "--tracker-max-distance"})
            if (given(o, option)) refuse(std::string(option) + " sets the tracker, which --poses groundtruth does not use");
    if (!o.device_uri.empty() && !o.live) refuse("--device-uri picks a live camera: it needs --live");
    if (o.live && (!o.source.empty() || !o.source_options.depth_pattern.empty()))
        refuse("--live reads a camera: give no SOURCE, --rgb or --depth with it");
    if (!o.source.empty() && !o.source_options.depth_pattern.empty() && app::SyntheticSource::isSyntheticName(o.source))
        refuse("--rgb/--depth name files: they cannot be used with a synthetic source");
    if (given(o, "--min-confidence") && !StrayScannerSource::isCapture(o.source))
        refuse("--min-confidence filters iPhone LiDAR depth: '" + o.source + "' is not a Stray Scanner capture");
    if (given(o, "--calib") && app::SyntheticSource::isSyntheticName(o.source))
        refuse("--calib replaces a recording's calibration: the synthetic source renders with its own");
    if (!o.load_map.empty() && o.max_frames == 0) {
        // Only the map is read: whatever reads, tracks or fuses frames would be ignored.
        for (const char* option : {"source", "--live", "--device-uri", "--threaded", "--min-confidence", "--rgb", "--depth", "--calib", "--skip",
                                   "--render-every", "--min-depth", "--max-depth", "--depth-gap-tolerance", "--occupancy", "--poses", "--tracker",
                                   "--tracker-config", "--tracker-levels", "--tracker-iterations", "--tracker-max-distance", "--labels",
                                   "--label-match", "--label-ignore", "--label-update", "--relocalise", "--relocalise-candidates",
                                   "--relocalise-max-speed"})
            if (given(o, option))
                refuse(std::string(option == std::string("source") ? "a SOURCE" : option) +
                       " concerns frames, and --load-map with --frames 0 reads none (leave it out, or give frames)");
    }
}

// Explicitly named output files are checked before the run, not when they are due after it.
// Called once the output folder exists: the paths may be in it.
void checkOutputPaths(const CliOptions& o) {
    if (!o.mesh_path.empty()) requireWritable(o.mesh_path);
    if (!o.save_map.empty()) requireWritable(o.save_map);
}

// With --load-map the map decides the voxel type, the index and its table, the voxel size and mu;
// giving another on the command line is an error rather than silently ignored. The block ceiling is
// the map's unless --max-blocks gives one: it bounds how far the map may grow on this machine, and a
// map that filled its ceiling elsewhere must be able to go on (the full-map warning says so).
void adoptMapSettings(CliOptions& o, const MapFileInfo& map) {
    MainEngineSettings adopted = settingsForMap(map, o.engine);
    if (given(o, "--max-blocks")) adopted.hash.max_block_count = o.engine.hash.max_block_count;
    auto conflict = [&](const char* option, const std::string& what) {
        throw ConfigError(o.load_map + ": the map has " + what + "; " + option + " cannot change it (leave the option out)");
    };
    if (!o.labels.voxel.empty() && o.labels.voxel != map.voxel_type) conflict("--voxel", "'" + map.voxel_type + "' voxels");
    if (given(o, "--index") && o.index != (map.hash ? "hash" : "dense")) conflict("--index", std::string("the ") + (map.hash ? "hash" : "dense") + " index");
    if (given(o, "--voxel-size") && o.engine.scene.voxel_size_m != map.scene.voxel_size_m)
        conflict("--voxel-size", std::to_string(map.scene.voxel_size_m) + " m voxels");
    if (given(o, "--mu") && o.engine.scene.mu_m != map.scene.mu_m) conflict("--mu", "mu " + std::to_string(map.scene.mu_m) + " m");
    if (given(o, "--max-blocks") && !map.hash) conflict("--max-blocks", "the dense index");
    for (const char* option : {"--hash-buckets", "--hash-excess", "--volume-size", "--volume-offset"})
        if (given(o, option)) conflict(option, "its own index settings");
    o.labels.voxel = map.voxel_type;
    o.index = map.hash ? "hash" : "dense";
    o.engine = adopted;
    o.dense_size = {adopted.dense_size.x, adopted.dense_size.y, adopted.dense_size.z};
    o.dense_offset = {adopted.dense_offset.x, adopted.dense_offset.y, adopted.dense_offset.z};
}

void applyDeviceAndIndex(const CliOptions& o, MainEngineSettings& s) {
    s.index_type = parseIndexType(o.index);
    if (o.active_blocks > 0 || !s.swap.swap_file.empty()) s.swap.enabled = true;
    if (o.active_blocks > 0) s.hash.max_block_count = o.active_blocks;
    s.device = o.device == "cuda" ? Device::CUDA : Device::CPU;
    s.dense_size = {o.dense_size[0], o.dense_size[1], o.dense_size[2]};
    s.dense_offset = {o.dense_offset[0], o.dense_offset[1], o.dense_offset[2]};
    s.tracker = trackerSettings(o);
}

void saveMapIfAsked(MainEngine& engine, const CliOptions& o, app::RunRecord& record) {
    if (o.save_map.empty()) return;
    const Timer t;
    engine.saveMap(o.save_map);
    record.map_saved = o.save_map;
    std::cerr << "voxfuse: map saved in " << int(t.elapsedMs()) << " ms -> " << o.save_map << "\n";
}

// --load-map with --frames 0: no source, only what the map gives (mesh, cloud, a render from the
// pose it was saved at, the map saved again).
int runOnMapAlone(CliOptions& o, const MapFileInfo& map) {
    if (!map.camera.valid()) throw ConfigError(o.load_map + ": the map has no camera to render from; give a SOURCE");
    MainEngineSettings& s = o.engine;
    s.voxel_type = parseVoxelType(map.voxel_type);
    applyDeviceAndIndex(o, s);
    RGBDCalib calib;
    calib.depth = calib.rgb = map.camera;
    std::unique_ptr<MainEngine> engine = MainEngine::create(s, calib);
    const Timer wall;
    engine->loadMap(o.load_map);
    app::OutputFolder out(o.out_dir, o.overwrite, "voxfuse");
    checkOutputPaths(o);
    app::RunRecord record;
    record.source = "map " + o.load_map + " (no frames)";
    record.settings = engine->settings();
    record.map_loaded = o.load_map;
    saveRenders(*engine, out, "map");
    writeMapOutputs(*engine, o, out);
    saveMapIfAsked(*engine, o, record);
    record.wall_s = wall.elapsedMs() / 1000.0;
    record.peak_rss_mb = app::peakRssMb();
    record.scene_mb = double(engine->sceneBytes()) / (1024.0 * 1024.0);
    record.allocation = engine->allocationStats();
    writeRunFiles(record, out, false);
    std::cout << app::summaryText(record, o.out_dir);
    return 0;
}

int run(CliOptions& o) {
    if (o.list_devices) {
        const std::vector<std::string> uris = OpenNISource::deviceUris();
        std::cout << (uris.empty() ? "no OpenNI2 camera found\n" : "OpenNI2 cameras:\n");
        for (const auto& uri : uris) std::cout << "  " << uri << "\n";
        return 0;
    }
    checkCombinations(o);
    MapFileInfo map;
    if (!o.load_map.empty()) {
        map = readMapFileInfo(o.load_map);
        adoptMapSettings(o, map);
        if (o.max_frames == 0) return runOnMapAlone(o, map);
    } else if (o.max_frames == 0) {
        throw ConfigError("--frames 0 processes no frame: it needs --load-map, a map to write outputs from");
    }
    std::unique_ptr<ImageSource> source;
    if (o.live) {
        source = OpenNISource::openDevice(o.device_uri, o.source_options);
    } else {
        if (o.source.empty() && o.source_options.rgb_pattern.empty() && o.source_options.depth_pattern.empty()) o.source = app::bundledSequence("voxfuse");
        if (app::SyntheticSource::isSyntheticName(o.source)) source = app::SyntheticSource::open(o.source);
        else source = openImageSource(o.source, o.source_options);
    }
    MainEngineSettings& s = o.engine;
    // Label images are decoded on the reader thread too: the stream goes inside it.
    LabelledImageSource* labels = app::attachLabelInput(source, o.source, o.labels, s, "voxfuse");
    // Before the run, not after it: a run must not end without its outputs over an option it cannot honour.
    if ((o.mesh_per_class || !o.exclude_classes.empty()) && !voxelTypeHasLabels(s.voxel_type))
        throw ConfigError("--mesh-per-class and --exclude-classes need a voxel type with classes (s_label, s_rgb_label)");
    // Frames reach the engine undistorted, read ahead on a reader thread with --threaded (always
    // for live cameras, so that the engine never makes the driver wait).
    source = framesForEngine(std::move(source), o.threaded);
    const auto* threaded = dynamic_cast<const ThreadedImageSource*>(source.get());
    std::cerr << "voxfuse: " << source->description() << "\n";

    applyDeviceAndIndex(o, s);

    std::unique_ptr<MainEngine> engine = MainEngine::create(s, source->calib());
    app::RunRecord record;
    if (!o.load_map.empty()) {
        engine->loadMap(o.load_map);
        record.map_loaded = o.load_map;
    }
    record.source = source->description();
    record.has_labels = labels != nullptr;
    record.settings = engine->settings();
    record.tracked = o.poses == "track";
    app::SequenceRunner runner(*source, *engine, record.tracked ? app::PoseSource::Tracker : app::PoseSource::GroundTruth, record);
    const int total = o.max_frames >= 0 && (source->frameCount() < 0 || o.max_frames < source->frameCount()) ? o.max_frames
                                                                                                                : source->frameCount();
    // The occupancy map is built on its own thread; the loop hands it each fused frame and never waits.
    std::unique_ptr<OccupancyMapper> occupancy;
    if (o.occupancy_res_m > 0.f) {
        OccupancySettings os;
        os.resolution_m = o.occupancy_res_m;
        occupancy = std::make_unique<OccupancyMapper>(os);
    }
    // Last: with --overwrite the folder loses the earlier run's outputs here, so everything that can
    // still refuse the run has run.
    app::OutputFolder out(o.out_dir, o.overwrite, "voxfuse");
    checkOutputPaths(o);
    if (o.skip_frames > 0) std::cerr << "voxfuse: skipped the first " << runner.skip(o.skip_frames) << " frames\n";
    ProgressLine progress(total);
    const Timer wall;
    int last_rendered = -1;
    while ((o.max_frames < 0 || int(record.frames.size()) < o.max_frames) && !app::interrupt::requested() && runner.step()) {
        const FrameResult& fr = runner.lastRecord().result;
        record.frames_with_labels += !runner.frame().labels.empty();
        if (occupancy && fr.fused) occupancy->submit(engine->view().depth, engine->view().calib.depth, fr.T_world_camera);
        if (o.render_every > 0 && int(record.frames.size() - 1) % o.render_every == 0) {
            saveRenders(*engine, out, runner.frame().index);
            last_rendered = runner.frame().index;
        }
        progress.update(int(record.frames.size()), double(record.frames.size()) / (wall.elapsedMs() / 1000.0));
    }
    record.wall_s = wall.elapsedMs() / 1000.0;
    record.interrupted = app::interrupt::requested();
    if (threaded) record.frames_dropped = int(threaded->droppedFrames());

    progress.finish();
    if (record.frames.empty() && !record.interrupted) throw ConfigError("no frame could be processed from " + source->description());
    if (!record.frames.empty() && last_rendered != record.frames.back().index) saveRenders(*engine, out, record.frames.back().index);

    record.peak_rss_mb = app::peakRssMb();
    record.scene_mb = double(engine->sceneBytes()) / (1024.0 * 1024.0);
    record.allocation = engine->allocationStats();
    if (!source->groundTruth().empty()) {
        record.trajectory_error = evaluateTrajectory(record.trajectory, source->groundTruth());
        record.has_trajectory_error = record.trajectory_error.pairs >= 3;
    }
    writeTumTrajectory(out.file("trajectory.txt"), record.trajectory);
    if (!record.frames.empty()) {
        writeMapOutputs(*engine, o, out);
        saveMapIfAsked(*engine, o, record);
    }
    if (occupancy) {
        const std::string path = out.file("occupancy.bt");
        writeFileAtomically(path, [&](const std::string& temporary) { occupancy->write(temporary); });  // drains the queue first
        const OccupancyStats st = occupancy->stats();
        std::cerr << "voxfuse: occupancy map " << st.frames_inserted << " frames inserted, " << st.frames_dropped
                  << " dropped while the mapper lagged, " << st.points_inserted << " points -> " << path << "\n";
    }
    writeRunFiles(record, out, true);
    std::cout << app::summaryText(record, o.out_dir);
    return app::interrupt::exitStatus();
}

}  // namespace

int main(int argc, char** argv) {
    app::useLongRunHeapPolicy();
    CLI::App cli{"VoxFuse: dense 3D reconstruction from RGB-D sequences.\n"
                 "With no SOURCE, runs on the bundled synthetic sequence.\n"
                 "Ctrl-C (or SIGTERM) stops after the current frame and writes the outputs of the frames done; a second one quits at once."};
    CliOptions o;
    cli.add_option("source", o.source,
                   "TUM RGB-D folder, per-frame folder (frame-XXXXXX.depth.png), OpenNI .oni recording, Stray Scanner (iPhone LiDAR) "
                   "folder, or synthetic[:N] / synthetic-corridor[:N] (rendered in memory)");
    cli.add_flag("--live", o.live, "read a live OpenNI2 camera (Kinect, PrimeSense, Structure)");
    cli.add_option("--device-uri", o.device_uri, "with --live: which camera (see --list-devices; default: the first)");
    cli.add_flag("--list-devices", o.list_devices, "list the OpenNI2 cameras and exit");
    cli.add_flag("--threaded", o.threaded, "decode and undistort frames on a reader thread ahead of the engine (always on for --live)");
    cli.add_option("--min-confidence", o.source_options.min_depth_confidence, "iPhone LiDAR: keep depth of at least this confidence (0-2)")
        ->capture_default_str()->check(app::intIn(0, 2));
    cli.add_option("--rgb", o.source_options.rgb_pattern, "PPM colour file pattern, e.g. frames/%04i.ppm");
    cli.add_option("--depth", o.source_options.depth_pattern, "16-bit PGM depth file pattern, e.g. frames/%04i.pgm");
    cli.add_option("--calib", o.source_options.calib_path, "InfiniTAM calib.txt (overrides the source's own)");
    cli.add_option("--out", o.out_dir, "output folder (refused when it holds an earlier run's outputs, unless --overwrite)")->capture_default_str();
    cli.add_flag("--overwrite", o.overwrite, "replace the outputs of an earlier run in the output folder (they are removed first)");
    cli.add_option("--frames", o.max_frames, "process at most N frames (default: all; 0 with --load-map: none, only the map's outputs)")
        ->check(app::nonNegativeInt());
    cli.add_flag("--swap", o.engine.swap.enabled,
                 "swapping: only the map near the view stays in the voxel array (--active-blocks), the rest goes to host memory "
                 "or --swap-file");
    cli.add_option("--active-blocks", o.active_blocks, "swapping: blocks the active voxel array holds at most (implies --swap)")
        ->check(app::positiveInt());
    cli.add_option("--swap-file", o.engine.swap.swap_file,
                   "swapping: keep the swapped-out map in this new file (an existing path is refused; deleted as it opens) "
                   "instead of memory (implies --swap)");
    cli.add_option("--swap-blocks-per-frame", o.engine.swap.blocks_per_frame, "swapping: blocks moved each way per frame at most")
        ->capture_default_str()->check(app::intIn(1, 1 << 20));
    cli.add_option("--skip", o.skip_frames, "drop the first N frames of the source (e.g. those a --load-map map already holds)")
        ->check(app::nonNegativeInt());
    cli.add_option("--save-map", o.save_map, "write the map to this file (.vfm) at the end, to continue or export it later");
    cli.add_option("--load-map", o.load_map,
                   "continue the map in this file (.vfm): its voxel type, index and voxel size are used, tracking resumes where it was "
                   "saved; with --frames 0 no SOURCE is read")
        ->check(CLI::ExistingFile);
    cli.add_option("--render-every", o.render_every, "write render_XXXXXX.png every N frames (0 = only the last)")
        ->capture_default_str()->check(app::nonNegativeInt());
    cli.add_option("--voxel-size", o.engine.scene.voxel_size_m, "voxel edge in metres")->capture_default_str()->check(app::floatIn(0.0, 1.0, true));
    cli.add_option("--mu", o.engine.scene.mu_m, "truncation band in metres")->capture_default_str()->check(app::floatIn(0.0, 10.0, true));
    cli.add_option("--max-weight", o.engine.scene.max_weight, "cap on the per-voxel weight")->capture_default_str()->check(app::intIn(1, 255));
    cli.add_option("--min-depth", o.engine.scene.view_frustum_min_m, "ignore depth below (m)")->capture_default_str()->check(app::floatIn(0.0, 1000.0));
    cli.add_option("--max-depth", o.engine.scene.view_frustum_max_m, "ignore depth beyond (m)")->capture_default_str()->check(app::floatIn(0.0, 1000.0, true));
    cli.add_option("--depth-gap-tolerance", o.engine.depth_gap_tolerance,
                   "fill a pixel without depth whose two neighbours (left-right, else up-down) agree within this fraction of their depth; 0 = never")
        ->capture_default_str()->check(app::floatIn(0.0, 0.5));
    app::addVoxelAndLabelOptions(cli, o.labels, "s_rgb");
    cli.add_option("--index", o.index, "voxel index")->capture_default_str()->check(CLI::IsMember({"dense", "hash"}));
    cli.add_option("--max-blocks", o.engine.hash.max_block_count,
                   "hash: most 8^3 voxel blocks (memory grows on demand up to this); 0 = automatic: as many as the hash has entries "
                   "and 3/4 of the device's free memory holds (on the GPU with room for the copy a growth makes)")
        ->capture_default_str()->check(app::intIn(0, 1 << 22));
    cli.add_option("--hash-buckets", o.engine.hash.bucket_count, "hash: number of ordered buckets")->capture_default_str()->check(app::positiveInt());
    cli.add_option("--hash-excess", o.engine.hash.excess_entry_count, "hash: entries in the excess list")->capture_default_str()->check(app::nonNegativeInt());
    cli.add_option("--volume-size", o.dense_size, "dense volume size in voxels (x y z)")->expected(3)->capture_default_str()->check(app::intIn(1, 1 << 16));
    cli.add_option("--volume-offset", o.dense_offset, "dense volume's first voxel, grid units (x y z)")
        ->expected(3)->capture_default_str()->check(app::intIn(-(1 << 24), 1 << 24));
    cli.add_option("--device", o.device, "where the frame loop runs and the map lives: cpu, or cuda for the GPU (image processing, tracking, fusion, raycast, meshes)")->capture_default_str()->check(CLI::IsMember({"cpu", "cuda"}));
    cli.add_flag("--mesh", o.write_mesh, "write the map's mesh (marching cubes) to DIR/mesh.ply at the end");
    cli.add_option("--mesh-file", o.mesh_path, "write the mesh to this file instead (.ply, .obj or .stl)")->check(app::meshFileName());
    cli.add_flag("--cloud", o.write_cloud, "write the surface points with normals (and colours) to DIR/cloud.ply");
    cli.add_option("--cloud-voxel", o.cloud_voxel_m, "downsample the cloud to one point (the centroid) per cell of M metres; implies --cloud")
        ->check(app::floatIn(1e-4, 1000.0));
    cli.add_option("--occupancy", o.occupancy_res_m, "also build an OctoMap with RES-metre cells on a background thread -> DIR/occupancy.bt")
        ->check(app::floatIn(0.001, 10.0));
    cli.add_flag("--mesh-per-class", o.mesh_per_class, "also write one mesh per semantic class: DIR/mesh_class_<id>.ply");
    cli.add_option("--exclude-classes", o.exclude_classes, "drop these classes from the mesh and the cloud (e.g. people from a static map)")
        ->delimiter(',')->check(app::intIn(0, 65535));
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
    cli.add_option("--tracker-iterations", o.tracker_iterations, "iterations per level, coarse to fine")->check(app::intIn(1, 1000));
    cli.add_option("--tracker-max-distance", o.tracker_max_distance, "ICP outlier distance per level (m), coarse to fine")
        ->check(app::floatIn(0.0, 10.0, true));
    app::addRelocalisationOptions(cli, o.engine.relocalisation);
    app::addVersionFlag(cli, "voxfuse");
    if (const auto status = app::parseCommandLine(cli, argc, argv, "voxfuse")) return *status;
    for (const CLI::Option* option : cli.get_options())
        if (option->count() > 0) o.given.push_back(option->get_name());  // "--index", or "source" for the positional

    app::interrupt::install("voxfuse");
    return app::runReportingErrors("voxfuse", [&] { return run(o); });
}
