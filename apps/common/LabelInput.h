#pragma once
// The voxel-type and semantic-label options every front-end shares (voxfuse, voxfuse_viewer,
// voxfuse_bench): the voxel type, where the label images come from, how they are matched to frames
// and fused. They are settled together because labels need a voxel type with classes.

#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/io/ImageSource.h"
#include "voxfuse/io/LabelledImageSource.h"

namespace voxfuse::app {

struct LabelInputOptions {
    std::string voxel;           // --voxel: "" = default_voxel, or s_rgb_label with --labels
    std::string default_voxel;   // the front-end's own default (set by addVoxelAndLabelOptions)
    std::string path;            // --labels: folder or list file; "" = SOURCE/labels.txt or SOURCE/labels/ if there
    std::string match = "auto";  // --label-match auto|index|timestamp
    int ignore_id = 0;           // --label-ignore: this id in the files means "no label" (-1: none)
    std::string update = "probabilistic";  // --label-update probabilistic|vote
};

// Adds --voxel (default `default_voxel`), --labels, --label-match, --label-ignore and --label-update.
void addVoxelAndLabelOptions(CLI::App& cli, LabelInputOptions& options, const std::string& default_voxel);

// Settles the voxel type and the label stream together, then wraps `source` in the stream:
// - --voxel given: that type; else s_rgb_label with --labels; else options.default_voxel;
// - --labels with a voxel type without classes: ConfigError (the labels would be silently dropped);
// - a voxel type with classes and no --labels: SOURCE/labels.txt or SOURCE/labels/ when there, else a
//   warning on stderr (the map gets no classes).
// Sets settings.voxel_type and settings.scene.label_update. Returns the label stream (owned by
// `source`), or nullptr without one.
LabelledImageSource* attachLabelInput(std::unique_ptr<ImageSource>& source, const std::string& source_path,
                                      const LabelInputOptions& options, MainEngineSettings& settings,
                                      const char* program);

}  // namespace voxfuse::app
