#include "LabelInput.h"

#include <filesystem>
#include <iostream>

#include "OptionChecks.h"
#include "voxfuse/core/Error.h"

namespace fs = std::filesystem;

namespace voxfuse::app {

void addLabelOptions(CLI::App& cli, LabelInputOptions& o) {
    cli.add_option("--labels", o.path,
                   "semantic label images (one class id per pixel; PNG, PGM or TIFF): a folder, or a list file of "
                   "'timestamp path' lines "
                   "(default: SOURCE/labels.txt or SOURCE/labels/ when a semantic voxel type is used)");
    cli.add_option("--label-match", o.match,
                   "how label images find their frames: by file order (index), by timestamp, or auto")
        ->capture_default_str()
        ->check(CLI::IsMember({"auto", "index", "timestamp"}));
    cli.add_option("--label-ignore", o.ignore_id, "class id that means 'no label' in the label images (-1: none)")
        ->capture_default_str()
        ->check(intIn(-1, 65535));
}

namespace {

// SOURCE/labels.txt, else SOURCE/labels/, else "".
std::string labelsBeside(const std::string& source_path) {
    if (source_path.empty() || !fs::is_directory(source_path)) return "";
    for (const char* name : {"labels.txt", "labels"})
        if (fs::exists(fs::path(source_path) / name)) return (fs::path(source_path) / name).string();
    return "";
}

}  // namespace

LabelledImageSource* attachLabelInput(std::unique_ptr<ImageSource>& source, const std::string& source_path,
                                      const LabelInputOptions& o, PipelineSettings& s, bool voxel_given,
                                      const char* program) {
    if (!voxel_given && !o.path.empty()) s.voxel = "s_rgb_label";
    const VoxelType type = parseVoxelType(s.voxel);
    if (!o.path.empty() && !voxelTypeHasLabels(type))
        throw ConfigError("--labels needs a voxel type with classes (s_label or s_rgb_label), not --voxel " + s.voxel);
    if (!voxelTypeHasLabels(type)) return nullptr;
    const std::string path = !o.path.empty() ? o.path : labelsBeside(source_path);
    if (path.empty()) {
        std::cerr << program << ": warning: no label images (--labels, or labels.txt / labels/ beside the source): "
                  << "the map will have no classes\n";
        return nullptr;
    }
    LabelStreamOptions lo;
    lo.path = path;
    lo.match = o.match == "index"       ? LabelStreamOptions::Match::Index
               : o.match == "timestamp" ? LabelStreamOptions::Match::Timestamp
                                        : LabelStreamOptions::Match::Automatic;
    lo.ignore_id = o.ignore_id;
    auto labelled = std::make_unique<LabelledImageSource>(std::move(source), lo);
    LabelledImageSource* raw = labelled.get();
    source = std::move(labelled);
    return raw;
}

}  // namespace voxfuse::app
