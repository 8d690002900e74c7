// voxfuse_viewer: the interactive front-end. Takes the same sources as the voxfuse CLI and shows the
// reconstruction as it grows, InfiniTAM style.

#include <CLI/CLI.hpp>
#include <charconv>
#include <filesystem>
#include <iostream>

#include "LabelInput.h"
#include "RelocalisationOptions.h"
#include "OptionChecks.h"
#include "HeapPolicy.h"
#include "CommandLine.h"
#include "DefaultData.h"
#include "ProgramMain.h"
#include "ViewerApp.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/UndistortedImageSource.h"


namespace fs = std::filesystem;
using namespace voxfuse;

namespace {

constexpr const char* kKeyHelp =
    "keys: n next frame | space run/pause | 1-5 shaded/colour/normals/depth/class (Tab cycles) | left-drag orbit, wheel zoom,\n"
    "      c back to the camera | m save mesh | s save map | p screenshot | r reset the map | q/Esc quit\n";

struct Options {
    std::string source;
    SourceOptions source_options;
    app::LabelInputOptions labels;  // and --voxel
    std::string index = "hash";
    std::string device = "cpu";
    std::string poses = "track";
    std::string size;
    std::string load_map;
    bool paused = false;
    MainEngineSettings engine;
    viewer::ViewerOptions viewer;
};

// "WxH" -> the window size; ConfigError for anything else.
void parseWindowSize(const std::string& text, viewer::ViewerOptions& out) {
    const auto x = text.find_first_of("xX");
    int width = 0, height = 0;
    auto number = [](const std::string& part, int& value) {
        const auto result = std::from_chars(part.data(), part.data() + part.size(), value);
        return !part.empty() && result.ec == std::errc() && result.ptr == part.data() + part.size();
    };
    if (x == std::string::npos || !number(text.substr(0, x), width) || !number(text.substr(x + 1), height) || width < 64 || height < 64 ||
        width > 16384 || height > 16384)
        throw ConfigError("--size must be WIDTHxHEIGHT, each 64 to 16384, e.g. 1200x640 (got '" + text + "')");
    out.window_width = width;
    out.window_height = height;
}

int run(Options& o) {
    if (o.source.empty() && o.source_options.rgb_pattern.empty() && o.source_options.depth_pattern.empty()) o.source = app::bundledSequence("voxfuse_viewer");
    if (!o.size.empty()) parseWindowSize(o.size, o.viewer);
    std::unique_ptr<ImageSource> source = openImageSource(o.source, o.source_options);
    MainEngineSettings& s = o.engine;
    if (!o.load_map.empty()) {
        // The map decides the voxel type, the index and the voxel size.
        const MapFileInfo map = readMapFileInfo(o.load_map);
        if (!o.labels.voxel.empty() && o.labels.voxel != map.voxel_type)
            throw ConfigError(o.load_map + ": the map has '" + map.voxel_type + "' voxels; --voxel cannot change it");
        o.labels.voxel = map.voxel_type;
        o.index = map.hash ? "hash" : "dense";
        s = settingsForMap(map, s);
    }
    app::attachLabelInput(source, o.source, o.labels, s, "voxfuse_viewer");
    source = framesForEngine(std::move(source), false);  // the same undistorted frames as voxfuse
    std::cerr << "voxfuse_viewer: " << source->description() << "\n";

    s.index_type = parseIndexType(o.index);
    s.device = o.device == "cuda" ? Device::CUDA : Device::CPU;
    std::unique_ptr<MainEngine> engine = MainEngine::create(s, source->calib());
    if (!o.load_map.empty()) engine->loadMap(o.load_map);

    o.viewer.poses = o.poses == "track" ? app::PoseSource::Tracker : app::PoseSource::GroundTruth;
    o.viewer.start_running = !o.paused || o.viewer.exit_when_done;  // --exit waits for processing to stop
    viewer::ViewerApp app(o.viewer, std::move(source), std::move(engine));
    std::cerr << kKeyHelp;
    return app.run();
}

}  // namespace

int main(int argc, char** argv) {
    app::useLongRunHeapPolicy();
    CLI::App cli{"VoxFuse viewer: watch the reconstruction grow, frame by frame.\n"
                 "With no SOURCE, runs on the bundled synthetic sequence.\n" + std::string(kKeyHelp)};
    Options o;
    cli.add_option("source", o.source, "TUM RGB-D folder, per-frame folder, Stray Scanner capture or .oni recording");
    cli.add_option("--rgb", o.source_options.rgb_pattern, "PPM colour file pattern, e.g. frames/%04i.ppm");
    cli.add_option("--depth", o.source_options.depth_pattern, "16-bit PGM depth file pattern, e.g. frames/%04i.pgm");
    cli.add_option("--calib", o.source_options.calib_path, "InfiniTAM calib.txt (overrides the source's own)");
    app::addVoxelAndLabelOptions(cli, o.labels, "s_rgb");
    cli.add_option("--index", o.index, "voxel index")->capture_default_str()->check(CLI::IsMember({"dense", "hash"}));
    cli.add_option("--voxel-size", o.engine.scene.voxel_size_m, "voxel edge in metres")->capture_default_str()->check(app::floatIn(0.0, 1.0, true));
    cli.add_option("--device", o.device, "where the frame loop runs and the map lives: cpu, or cuda for the GPU (image processing, tracking, fusion, raycast, meshes)")->capture_default_str()->check(CLI::IsMember({"cpu", "cuda"}));
    cli.add_option("--poses", o.poses, "track the camera, or take the source's ground truth")
        ->capture_default_str()->check(CLI::IsMember({"track", "groundtruth"}));
    app::addRelocalisationOptions(cli, o.engine.relocalisation);
    cli.add_option("--out", o.viewer.out_dir, "folder for the mesh (m), the map (s) and screenshot (p)")->capture_default_str();
    cli.add_option("--load-map", o.load_map, "continue the map in this file (.vfm; see voxfuse --save-map and key s)")->check(CLI::ExistingFile);
    cli.add_option("--frames", o.viewer.max_frames, "stop processing after N frames (0 = all)")->check(app::nonNegativeInt());
    cli.add_flag("--paused", o.paused, "start paused (n steps, space runs)");
    cli.add_option("--size", o.size, "window size WIDTHxHEIGHT (default 1200x640)");
    cli.add_option("--screenshot", o.viewer.screenshot_path, "save the window as PNG once processing stops (end of source or --frames)");
    cli.add_flag("--exit", o.viewer.exit_when_done, "quit once processing stops (after --screenshot); for scripts and tests");
    app::addVersionFlag(cli, "voxfuse_viewer");
    if (const auto status = app::parseCommandLine(cli, argc, argv, "voxfuse_viewer")) return *status;
    return app::runReportingErrors("voxfuse_viewer", [&] { return run(o); });
}
