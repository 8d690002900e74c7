#pragma once
// The main engine with MainEngineSettings::submaps: the map as local submaps, each a main engine of
// its own (its own voxel block hash, tracker state and keyframes) with a pose in the world; the
// submaps' poses are the nodes of a pose graph (mapping/PoseGraph.h) solved on its own thread.
// MainEngine::create makes one when the settings ask for submaps.

#include <memory>

#include "voxfuse/engines/MainEngine.h"

namespace voxfuse {

std::unique_ptr<MainEngine> makeSubmapEngine(const MainEngineSettings& checked_settings, const RGBDCalib& calib);

}  // namespace voxfuse
