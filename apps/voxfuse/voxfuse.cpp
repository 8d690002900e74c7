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
#include "MergeCommand.h"
#include "OptionChecks.h"
#include "OutputFolder.h"
#include "PipelineOptions.h"
#include "HeapPolicy.h"
#include "CommandLine.h"
#include "ProgramMain.h"
#include "ResourceUsage.h"
#include "RunRecord.h"
#include "SequenceRunner.h"
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
#include "voxfuse/io/ThreadedImageSource.h"
#include "voxfuse/mapping/OccupancyMapper.h"

namespace fs = std::filesystem;
using namespace voxfuse;

namespace {

// Exit status of a run that wrote its outputs but added nothing to the map (2: an error refused the run).
constexpr int kExitNothingFused = 4;

struct CliOptions {
    app::PipelineOptions pipeline;  // the source, the map and the tracker (shared with the viewer)
    std::string out_dir = "voxfuse_out";
    bool overwrite = false;  // replace an earlier run's outputs in out_dir
    int max_frames = -1;     // -1 = all; 0 = none (with --load-map: the map's outputs only)
    int render_every = 25;
    bool write_mesh = false;           // DIR/mesh.ply at the end
    std::string mesh_path;             // or this file (.ply, .obj, .stl)
    bool write_cloud = false;          // DIR/cloud.ply at the end
    float cloud_voxel_m = 0.f;         // downsample the cloud to one point per cell of this size
    float occupancy_res_m = 0.f;       // > 0: an OctoMap with cells of this size -> DIR/occupancy.bt
    bool mesh_per_class = false;       // DIR/mesh_class_<id>.ply for each class of the mesh
    std::vector<int> exclude_classes;  // dropped from the mesh and the cloud (e.g. people from a static map)
    std::string save_map;              // write the map here at the end
};

class ProgressLine {
public:
    explicit ProgressLine(int total) : total_(total), tty_(isatty(STDERR_FILENO)) {}
    void update(int done, double fps) {
        if (!tty_) return;
        if (total_ > 0)
            std::fprintf(stderr, "\r  frame %d/%d  %.1f fps   ", done, total_, fps);
        else
            std::fprintf(stderr, "\r  frame %d  %.1f fps   ", done, fps);
        std::fflush(stderr);
    }
    void finish() {
        if (tty_) std::fprintf(stderr, "\n");
    }

private:
    int total_;
    bool tty_;
};

std::vector<ClassId> excludedClasses(const CliOptions& o) {
    return std::vector<ClassId>(o.exclude_classes.begin(), o.exclude_classes.end());
}

// The mesh's extraction time goes into `record` (summary.json).
void writeMapOutputs(MainEngine& engine, const CliOptions& o, app::OutputFolder& out, app::RunRecord& record) {
    if (o.write_mesh || !o.mesh_path.empty() || o.mesh_per_class) {
        const Timer t;
        Mesh mesh;
        engine.extractMesh(mesh);
        record.mesh_ms = t.elapsedMs();
        if (!o.exclude_classes.empty()) mesh = selectClasses(mesh, excludedClasses(o), ClassSelection::Exclude);
        if (o.write_mesh || !o.mesh_path.empty()) {
            const std::string path = o.mesh_path.empty() ? out.file("mesh.ply") : o.mesh_path;
            writeMesh(path, mesh);
            std::cerr << "voxfuse: mesh " << mesh.vertices.size() << " vertices, " << mesh.triangles.size()
                      << " triangles in " << int(t.elapsedMs()) << " ms -> " << path << "\n";
        }
        if (o.mesh_per_class) {
            for (const ClassMesh& part : splitByClass(mesh)) {
                const bool unlabelled = part.label == kNoLabel;
                const std::string part_path =
                    out.file(unlabelled ? "mesh_unlabelled.ply" : "mesh_class_" + std::to_string(part.label) + ".ply");
                writeMesh(part_path, part.mesh);
                std::cerr << "voxfuse: class " << (unlabelled ? std::string("none") : std::to_string(part.label))
                          << ": " << part.mesh.triangles.size() << " triangles -> " << part_path << "\n";
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
        std::cerr << "voxfuse: point cloud " << cloud.points.size() << " points (of " << surface_points
                  << " surface points) -> " << path << "\n";
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

// Options that would be silently ignored in this combination are errors instead: those of the
// pipeline (app::checkPipelineOptions), and what --load-map with --frames 0 leaves unread.
void checkCombinations(const CliOptions& o) {
    const app::PipelineOptions& p = o.pipeline;
    app::checkPipelineOptions(p);
    if (!p.load_map.empty() && o.max_frames == 0) {
        // Only the map is read: whatever reads, tracks or fuses frames would be ignored.
        for (const char* option : {"source",
                                   "--live",
                                   "--device-uri",
                                   "--threaded",
                                   "--min-confidence",
                                   "--rgb",
                                   "--depth",
                                   "--calib",
                                   "--skip",
                                   "--render-every",
                                   "--min-depth",
                                   "--max-depth",
                                   "--depth-gap-tolerance",
                                   "--occupancy",
                                   "--poses",
                                   "--tracker",
                                   "--tracker-config",
                                   "--tracker-levels",
                                   "--tracker-iterations",
                                   "--tracker-max-distance",
                                   "--labels",
                                   "--label-match",
                                   "--label-ignore",
                                   "--label-update",
                                   "--relocalise",
                                   "--relocalise-candidates",
                                   "--relocalise-max-speed",
                                   "--relocalise-min-color-correlation",
                                   "--relocalise-min-colour-correlation"})
            if (p.wasGiven(option))
                throw ConfigError(
                    std::string(option == std::string("source") ? "a SOURCE" : option) +
                    " concerns frames, and --load-map with --frames 0 reads none (leave it out, or give frames)");
    }
}

// Explicitly named output files are checked before the run, not when they are due after it.
// Called once the output folder exists: the paths may be in it.
void checkOutputPaths(const CliOptions& o) {
    if (!o.mesh_path.empty()) requireWritable(o.mesh_path);
    if (!o.save_map.empty()) requireWritable(o.save_map);
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
    const app::PipelineOptions& p = o.pipeline;
    if (!map.camera.valid()) throw ConfigError(p.load_map + ": the map has no camera to render from; give a SOURCE");
    const MainEngineSettings s = app::engineSettings(p);
    RGBDCalib calib;
    calib.depth = calib.rgb = map.camera;
    std::unique_ptr<MainEngine> engine = MainEngine::create(s, calib);
    const Timer wall;
    engine->loadMap(p.load_map);
    app::OutputFolder out(o.out_dir, o.overwrite, "voxfuse");
    checkOutputPaths(o);
    app::RunRecord record;
    record.source = "map " + p.load_map + " (no frames)";
    record.settings = engine->settings();
    record.map_loaded = p.load_map;
    saveRenders(*engine, out, "map");
    writeMapOutputs(*engine, o, out, record);
    saveMapIfAsked(*engine, o, record);
    record.wall_s = wall.elapsedMs() / 1000.0;
    record.peak_rss_mb = app::peakRssMb();
    record.scene_mb = double(engine->sceneBytes()) / (1024.0 * 1024.0);
    record.allocation = engine->allocationStats();
    record.submaps = engine->submapCount();
    record.loop_closures = engine->loopClosures();
    record.pose_graph = engine->poseGraphSolves();
    writeRunFiles(record, out, false);
    std::cout << app::summaryText(record, o.out_dir);
    return 0;
}

int run(CliOptions& o) {
    app::PipelineOptions& p = o.pipeline;
    if (p.list_devices) {
        app::listCameras();
        return 0;
    }
    checkCombinations(o);
    MapFileInfo map;
    if (!p.load_map.empty()) {
        map = readMapFileInfo(p.load_map);
        app::adoptMapSettings(p, map);
        if (o.max_frames == 0) return runOnMapAlone(o, map);
    } else if (o.max_frames == 0) {
        throw ConfigError("--frames 0 processes no frame: it needs --load-map, a map to write outputs from");
    }
    app::Pipeline pipeline = app::openPipeline(p, "voxfuse");
    ImageSource* source = pipeline.source.get();
    MainEngine* engine = pipeline.engine.get();
    // Before the run, not after it: a run must not end without its outputs over an option it cannot honour.
    if ((o.mesh_per_class || !o.exclude_classes.empty()) && !voxelTypeHasLabels(engine->settings().voxel_type))
        throw ConfigError(
            "--mesh-per-class and --exclude-classes need a voxel type with classes (s_label, s_rgb_label)");
    const auto* threaded = dynamic_cast<const ThreadedImageSource*>(source);
    app::RunRecord record;
    record.map_loaded = p.load_map;
    record.source = source->description();
    record.has_labels = pipeline.labels != nullptr;
    record.settings = engine->settings();
    record.tracked = p.poses == "track";
    app::SequenceRunner runner(
        *source, *engine, record.tracked ? app::PoseSource::Tracker : app::PoseSource::GroundTruth, record, "voxfuse");
    const int total = o.max_frames >= 0 && (source->frameCount() < 0 || o.max_frames < source->frameCount())
                          ? o.max_frames
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
    if (p.skip_frames > 0) std::cerr << "voxfuse: skipped the first " << runner.skip(p.skip_frames) << " frames\n";
    ProgressLine progress(total);
    const Timer wall;
    int last_rendered = -1;
    while ((o.max_frames < 0 || int(record.frames.size()) < o.max_frames) &&
           runner.processNext(app::interrupt::requested)) {
        const FrameResult& fr = runner.lastRecord().result;
        record.frames_with_labels += !runner.frame().labels.empty();
        if (occupancy && fr.fused)
            occupancy->submit(engine->view().depth, engine->view().calib.depth, fr.T_world_camera);
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
    if (record.frames.empty() && !record.interrupted)
        throw ConfigError("no frame could be processed from " + source->description());
    // No frame follows: the frame loop's buffers (pyramids, raycasts, the view; 26 MB on teddy) make room
    // for the outputs' own, which else came on top of them when the map is largest.
    engine->releaseFrameMemory();
    if (!record.frames.empty() && last_rendered != record.frames.back().index)
        saveRenders(*engine, out, record.frames.back().index);

    record.peak_rss_mb = app::peakRssMb();
    record.scene_mb = double(engine->sceneBytes()) / (1024.0 * 1024.0);
    record.allocation = engine->allocationStats();
    record.submaps = engine->submapCount();
    record.loop_closures = engine->loopClosures();
    record.pose_graph = engine->poseGraphSolves();
    if (std::vector<Mat4f> optimised; engine->optimisedPoses(optimised)) {
        record.trajectory_online = record.trajectory;
        record.trajectory = withPoses(record.trajectory, optimised);
        writeTumTrajectory(out.file("trajectory_online.txt"), record.trajectory_online);
    }
    if (!source->groundTruth().empty()) {
        record.trajectory_error = evaluateTrajectory(record.trajectory, source->groundTruth());
        record.has_trajectory_error = record.trajectory_error.pairs >= 3;
        if (!record.trajectory_online.empty())
            record.trajectory_error_online = evaluateTrajectory(record.trajectory_online, source->groundTruth());
    }
    writeTumTrajectory(out.file("trajectory.txt"), record.trajectory);
    if (!record.frames.empty()) {
        writeMapOutputs(*engine, o, out, record);
        saveMapIfAsked(*engine, o, record);
    }
    if (occupancy) {
        const std::string path = out.file("occupancy.bt");
        writeFileAtomically(
            path, [&](const std::string& temporary) { occupancy->write(temporary); });  // drains the queue first
        const OccupancyStats st = occupancy->stats();
        std::cerr << "voxfuse: occupancy map " << st.frames_inserted << " frames inserted, " << st.frames_dropped
                  << " dropped while the mapper lagged, " << st.points_inserted << " points -> " << path << "\n";
    }
    writeRunFiles(record, out, true);
    std::cout << app::summaryText(record, o.out_dir);
    // The outputs stay, but a script must notice a run that added nothing to the map.
    const std::string nothing = app::nothingFusedReason(record);
    if (!nothing.empty()) {
        std::cerr << "voxfuse: error: " << nothing << "\n";
        return kExitNothingFused;
    }
    return app::interrupt::exitStatus();
}

}  // namespace

int main(int argc, char** argv) {
    app::useLongRunHeapPolicy();
    if (argc > 1 && std::string(argv[1]) == "merge")
        return app::runReportingErrors("voxfuse merge", [&] { return app::runMergeCommand(argc - 1, argv + 1); });
    CLI::App cli{
        "VoxFuse: dense 3D reconstruction from RGB-D sequences.\n"
        "With no SOURCE, runs on the bundled synthetic sequence. `voxfuse merge --help`: joining maps.\n"
        "Ctrl-C (or SIGTERM) stops after the current frame and writes the outputs of the frames done; a second one "
        "quits at once.\n"
        "Exit status: 0 done, 2 refused (the error says why), 3 an unexpected error, 4 ran but fused nothing "
        "into the map, 128+N stopped by signal N."};
    CliOptions o;
    app::addSourceOptions(cli, o.pipeline);
    cli.add_option("--out", o.out_dir,
                   "output folder (refused when it holds an earlier run's outputs, unless --overwrite)")
        ->capture_default_str();
    cli.add_flag("--overwrite", o.overwrite,
                 "replace the outputs of an earlier run in the output folder (they are removed first)");
    cli.add_option("--frames", o.max_frames,
                   "process at most N frames (default: all; 0 with --load-map: none, only the map's outputs)")
        ->check(app::nonNegativeInt());
    cli.add_option("--save-map", o.save_map,
                   "write the map to this file (.vfm) at the end, to continue or export it later");
    cli.add_option("--load-map", o.pipeline.load_map,
                   "continue the map in this file (.vfm): its voxel type, index, voxel size and submaps are used; "
                   "the first frame is found in it from where it was saved or by its keyframes (a new recording "
                   "of the place may start anywhere in it); with --frames 0 no SOURCE is read")
        ->check(CLI::ExistingFile);
    cli.add_option("--render-every", o.render_every, "write render_XXXXXX.png every N frames (0 = only the last)")
        ->capture_default_str()
        ->check(app::nonNegativeInt());
    app::addMapOptions(cli, o.pipeline);
    cli.add_flag("--mesh", o.write_mesh, "write the map's mesh (marching cubes) to DIR/mesh.ply at the end");
    cli.add_option("--mesh-file", o.mesh_path, "write the mesh to this file instead (.ply, .obj or .stl)")
        ->check(app::meshFileName());
    cli.add_flag("--cloud", o.write_cloud, "write the surface points with normals (and colours) to DIR/cloud.ply");
    cli.add_option("--cloud-voxel", o.cloud_voxel_m,
                   "downsample the cloud to one point (the centroid) per cell of M metres; implies --cloud")
        ->check(app::floatIn(1e-4, 1000.0));
    cli.add_option("--occupancy", o.occupancy_res_m,
                   "also build an OctoMap with RES-metre cells on a background thread -> DIR/occupancy.bt")
        ->check(app::floatIn(0.001, 10.0));
    cli.add_flag("--mesh-per-class", o.mesh_per_class,
                 "also write one mesh per semantic class: DIR/mesh_class_<id>.ply");
    cli.add_option("--exclude-classes", o.exclude_classes,
                   "drop these classes from the mesh and the cloud (e.g. people from a static map)")
        ->delimiter(',')
        ->check(app::intIn(0, 65535));
    app::addTrackingOptions(cli, o.pipeline);
    app::addVersionFlag(cli, "voxfuse");
    if (const auto status = app::parseCommandLine(cli, argc, argv, "voxfuse")) return *status;
    app::noteGivenOptions(cli, o.pipeline);

    app::interrupt::install("voxfuse");
    return app::runReportingErrors("voxfuse", [&] { return run(o); });
}
