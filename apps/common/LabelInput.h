#pragma once
// The semantic-label options every front-end shares (voxfuse, voxfuse_viewer, voxfuse_bench): where
// the label images come from and how they are matched to frames. The voxel type (--voxel) and the
// label update (--label-update) are settings (EngineOptions.h); the type is settled here with the
// labels, because labels need a voxel type with classes.

#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "voxfuse/engines/PipelineSettings.h"
#include "voxfuse/io/ImageSource.h"
#include "voxfuse/io/LabelledImageSource.h"

namespace voxfuse::app {

struct LabelInputOptions {
    std::string path;            // --labels: folder or list file; "" = SOURCE/labels.txt or SOURCE/labels/ if there
    std::string match = "auto";  // --label-match auto|index|timestamp
    int ignore_id = 0;           // --label-ignore: this id in the files means "no label" (-1: none)
};

// Adds --labels, --label-match and --label-ignore.
void addLabelOptions(CLI::App& cli, LabelInputOptions& options);

// Settles the voxel type and the label stream together, then wraps `source` in the stream:
// - --voxel given (`voxel_given`): that type; else s_rgb_label with --labels; else settings.voxel;
// - --labels with a voxel type without classes: ConfigError (the labels would be silently dropped);
// - a voxel type with classes and no --labels: SOURCE/labels.txt or SOURCE/labels/ when there, else a
//   warning on stderr (the map gets no classes).
// Sets settings.voxel. Returns the label stream (owned by `source`), or nullptr without one.
LabelledImageSource* attachLabelInput(std::unique_ptr<ImageSource>& source, const std::string& source_path,
                                      const LabelInputOptions& options, PipelineSettings& settings, bool voxel_given,
                                      const char* program);

}  // namespace voxfuse::app
