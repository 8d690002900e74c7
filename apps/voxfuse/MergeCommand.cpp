// voxfuse merge: the first map is loaded as a map of submaps, each further one merged into it, and the
// result written once, after every merge succeeded.

#include "MergeCommand.h"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "CommandLine.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/core/Timer.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/engines/PipelineSettings.h"
#include "voxfuse/io/AtomicFile.h"
#include "voxfuse/io/MapFile.h"

namespace voxfuse::app {

int runMergeCommand(int argc, char** argv) {
    CLI::App cli{
        "voxfuse merge: joins maps of the same place, made separately (.vfm files of one voxel type, voxel size "
        "and mu), into one map of submaps. Views of each further map are recognised in the first and verified as "
        "relocalisation verifies a pose; the pose graph places its submaps. A map of which no view is found is "
        "an error, and nothing is written."};
    std::vector<std::string> maps;
    std::string out;
    cli.add_option("maps", maps, "the maps: the first is the world of the result")
        ->required()
        ->check(CLI::ExistingFile);
    cli.add_option("--out", out, "the merged map (.vfm), written once every map is merged")->required();
    if (const auto status = parseCommandLine(cli, argc, argv, "voxfuse merge")) return *status;
    if (maps.size() < 2)
        throw ConfigError("voxfuse merge needs at least two maps (got " + std::to_string(maps.size()) + ")");
    requireWritable(out);

    const MapFileInfo info = readMapFileInfo(maps[0]);
    if (!info.camera.valid()) throw ConfigError(maps[0] + ": the map has no camera to render its views with");
    PipelineSettings settings;
    settings.adopt(info);
    settings.submaps = true;
    RGBDCalib calib;
    calib.depth = calib.rgb = info.camera;
    std::unique_ptr<MainEngine> engine = MainEngine::create(settingsForMap(info, settings.toEngineSettings()), calib);
    engine->loadMap(maps[0]);
    for (std::size_t i = 1; i < maps.size(); ++i) {
        const int before = engine->submapCount();
        const Timer t;
        const std::vector<LoopClosure> joins = engine->mergeMap(maps[i]);
        std::printf("voxfuse merge: %s: %d submaps joined by %zu verified views in %.1f s\n", maps[i].c_str(),
                    engine->submapCount() - before, joins.size(), t.elapsedMs() / 1000.0);
        for (const LoopClosure& j : joins)
            std::printf("  submap %d found in submap %d: residual %.1f mm, inliers %.0f%%\n", j.to_submap,
                        j.from_submap, 1000.0 * j.residual_m, 100.0 * j.inlier_ratio);
    }
    std::vector<Mat4f> unused;
    engine->optimisedPoses(unused);  // waits for the pose graph's solve
    int rejected = 0;
    for (const LoopClosure& l : engine->loopClosures()) rejected += l.rejected ? 1 : 0;
    engine->saveMap(out);
    std::printf("voxfuse merge: %d submaps, %d joins rejected by the pose graph -> %s\n", engine->submapCount(),
                rejected, out.c_str());
    return 0;
}

}  // namespace voxfuse::app
