#pragma once
// The main engine's settings checked before anything is allocated (src/engines/MainEngineSettings.cpp).

#include <string>

#include "voxfuse/engines/MainEngine.h"

namespace voxfuse {

// `requested` with the automatic block ceiling filled in (automaticMaxBlockCount, from the free memory of
// the device), checked: ConfigError or DeviceError naming the setting and its remedy otherwise, also when
// the index would not fit in the memory this machine has now.
MainEngineSettings checkedMainEngineSettings(const MainEngineSettings& requested, const RGBDCalib& calib);

// "the hash table of N entries needs X GiB", and what to change when that is too much.
std::string indexMemoryNeed(const MainEngineSettings& settings);
std::string indexRemedy(const MainEngineSettings& settings);

}  // namespace voxfuse
