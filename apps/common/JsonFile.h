#pragma once
// JSON reports (summary.json, timings.json, voxfuse_bench.json) through nlohmann-json, keys in the
// order they were added.

#include <nlohmann/json.hpp>
#include <string>

namespace voxfuse::app {

using Json = nlohmann::ordered_json;

// Writes `json` to `path`, indented, under a temporary name renamed into place (io/AtomicFile.h).
// Bytes of strings that are not UTF-8 (a path may hold any bytes) are written as U+FFFD, so that the
// file is valid JSON whatever it holds; NaN and infinities are written as null.
void writeJsonFile(const std::string& path, const Json& json);

}  // namespace voxfuse::app
