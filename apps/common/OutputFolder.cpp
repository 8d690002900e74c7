#include "OutputFolder.h"

#include <algorithm>
#include <filesystem>
#include <iostream>

#include "voxfuse/core/Error.h"
#include "voxfuse/io/AtomicFile.h"

namespace fs = std::filesystem;

namespace voxfuse::app {

namespace {

bool startsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }
bool endsWith(const std::string& s, const std::string& suffix) {
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// "summary.json, trajectory.txt and 12 more".
std::string listed(const std::vector<std::string>& names) {
    std::string text;
    const std::size_t shown = std::min<std::size_t>(names.size(), 4);
    for (std::size_t i = 0; i < shown; ++i) text += (i == 0 ? "" : ", ") + names[i];
    if (names.size() > shown) text += " and " + std::to_string(names.size() - shown) + " more";
    return text;
}

}  // namespace

bool isRunOutputName(const std::string& name) {
    for (const char* exact : {"trajectory.txt", "trajectory_online.txt", "timings.json", "summary.json", "mesh.ply",
                              "mesh_unlabelled.ply", "cloud.ply", "occupancy.bt"})
        if (name == exact) return true;
    if ((startsWith(name, "render_") && endsWith(name, ".png")) ||
        (startsWith(name, "mesh_class_") && endsWith(name, ".ply")))
        return true;
    return isPartialFileName(name);
}

OutputFolder::OutputFolder(const std::string& folder, bool overwrite, const char* program) : folder_(folder) {
    std::error_code ec;
    if (fs::exists(folder_, ec) && !fs::is_directory(folder_, ec))
        throw ConfigError("--out " + folder_ + ": is a file, not a folder");
    fs::create_directories(folder_, ec);
    if (ec) throw IoError(folder_, "cannot create the output folder: " + ec.message());

    std::vector<std::string> earlier;
    for (fs::directory_iterator it(folder_, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (isRunOutputName(name)) earlier.push_back(name);
    }
    if (ec) throw IoError(folder_, "cannot list the output folder: " + ec.message());
    std::sort(earlier.begin(), earlier.end());
    if (!earlier.empty() && !overwrite)
        throw ConfigError("--out " + folder_ + " holds the outputs of an earlier run (" + listed(earlier) +
                          "): give another --out, or --overwrite to replace them");
    for (const std::string& name : earlier) {
        fs::remove(fs::path(folder_) / name, ec);
        if (ec)
            throw IoError((fs::path(folder_) / name).string(),
                          "cannot remove an earlier run's output: " + ec.message());
    }
    if (!earlier.empty())
        std::cerr << program << ": --overwrite: removed " << earlier.size() << " files of an earlier run from "
                  << folder_ << " (" << listed(earlier) << ")\n";
    requireWritable((fs::path(folder_) / "summary.json").string());
}

std::string OutputFolder::file(const std::string& name) {
    if (std::find(written_.begin(), written_.end(), name) == written_.end()) written_.push_back(name);
    return (fs::path(folder_) / name).string();
}

}  // namespace voxfuse::app
