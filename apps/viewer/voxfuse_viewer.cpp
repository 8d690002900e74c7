// voxfuse_viewer: the interactive front-end. Takes the same sources (a live camera too) and the same
// map and tracker options as the voxfuse CLI, and shows the reconstruction as it grows, InfiniTAM style.

#include <CLI/CLI.hpp>
#include <charconv>
#include <filesystem>
#include <iostream>

#include "OptionChecks.h"
#include "PipelineOptions.h"
#include "HeapPolicy.h"
#include "CommandLine.h"
#include "ProgramMain.h"
#include "ViewerApp.h"
#include "voxfuse/core/Error.h"

namespace fs = std::filesystem;
using namespace voxfuse;

namespace {

constexpr const char* kKeyHelp =
    "keys: n next frame | space run/pause | 1-5 shaded/colour/normals/depth/class (Tab cycles) | left-drag orbit, "
    "wheel zoom,\n"
    "      c back to the camera | m save mesh | s save map | p screenshot | r reset the map | q/Esc quit\n";

struct Options {
    app::PipelineOptions pipeline;  // the source, the map and the tracker: what voxfuse takes
    std::string size;
    bool paused = false;
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
    if (x == std::string::npos || !number(text.substr(0, x), width) || !number(text.substr(x + 1), height) ||
        width < 64 || height < 64 || width > 16384 || height > 16384)
        throw ConfigError("--size must be WIDTHxHEIGHT, each 64 to 16384, e.g. 1200x640 (got '" + text + "')");
    out.window_width = width;
    out.window_height = height;
}

int run(Options& o) {
    app::PipelineOptions& p = o.pipeline;
    if (p.list_devices) {
        app::listCameras();
        return 0;
    }
    app::checkPipelineOptions(p);
    if (!o.size.empty()) parseWindowSize(o.size, o.viewer);
    if (!p.load_map.empty()) app::adoptMapSettings(p, readMapFileInfo(p.load_map));
    app::Pipeline pipeline = app::openPipeline(p, "voxfuse_viewer");  // the same frames and engine as voxfuse's

    o.viewer.poses = p.poses == "track" ? app::PoseSource::Tracker : app::PoseSource::GroundTruth;
    o.viewer.skip_frames = p.skip_frames;
    o.viewer.start_running = !o.paused || o.viewer.exit_when_done;  // --exit waits for processing to stop
    viewer::ViewerApp app(o.viewer, std::move(pipeline.source), std::move(pipeline.engine));
    std::cerr << kKeyHelp;
    return app.run();
}

}  // namespace

int main(int argc, char** argv) {
    app::useLongRunHeapPolicy();
    CLI::App cli{
        "VoxFuse viewer: watch the reconstruction grow, frame by frame.\n"
        "With no SOURCE, runs on the bundled synthetic sequence.\n" +
        std::string(kKeyHelp)};
    Options o;
    app::addSourceOptions(cli, o.pipeline);
    app::addMapOptions(cli, o.pipeline);
    app::addTrackingOptions(cli, o.pipeline);
    cli.add_option("--out", o.viewer.out_dir, "folder for the mesh (m), the map (s) and screenshot (p)")
        ->capture_default_str();
    cli.add_option("--load-map", o.pipeline.load_map,
                   "continue the map in this file (.vfm; see voxfuse --save-map and key s): its voxel type, index, "
                   "voxel size and submaps are used; the first frame is found in it")
        ->check(CLI::ExistingFile);
    cli.add_option("--frames", o.viewer.max_frames, "stop processing after N frames (0 = all)")
        ->check(app::nonNegativeInt());
    cli.add_flag("--paused", o.paused, "start paused (n steps, space runs)");
    cli.add_option("--size", o.size, "window size WIDTHxHEIGHT (default 1200x640)");
    cli.add_option("--screenshot", o.viewer.screenshot_path,
                   "save the window as PNG once processing stops (end of source or --frames)")
        ->check(
            [](const std::string& path) {
                // Refused before the run rather than after it: the file is written once processing stops.
                const std::string ext = std::filesystem::path(path).extension().string();
                return ext == ".png" || ext == ".PNG" ? std::string()
                                                      : "the screenshot is a PNG file: its name must end in .png";
            },
            "PNG");
    cli.add_flag("--exit", o.viewer.exit_when_done,
                 "quit once processing stops (after --screenshot); for scripts and tests");
    app::addVersionFlag(cli, "voxfuse_viewer");
    if (const auto status = app::parseCommandLine(cli, argc, argv, "voxfuse_viewer")) return *status;
    app::noteGivenOptions(cli, o.pipeline);
    return app::runReportingErrors("voxfuse_viewer", [&] { return run(o); });
}
