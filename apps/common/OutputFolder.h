#pragma once
// A run's output folder. It is created when missing; outputs of an earlier run found in it are
// refused, or with `overwrite` removed first and named, so that no file of an earlier run is ever
// taken for this run's. The folder is checked to be writable before the run starts rather than
// when its outputs are due.

#include <string>
#include <vector>

namespace voxfuse::app {

class OutputFolder {
public:
    // Throws ConfigError when the folder holds an earlier run's outputs and `overwrite` is false, or
    // when `folder` is a file; IoError when it cannot be created or written. `program` prefixes the
    // line that lists what --overwrite removed.
    OutputFolder(const std::string& folder, bool overwrite, const char* program);

    // folder/name, recorded as one of this run's outputs.
    std::string file(const std::string& name);
    // The outputs recorded so far, in the order they were asked for.
    const std::vector<std::string>& written() const { return written_; }
    const std::string& folder() const { return folder_; }

private:
    std::string folder_;
    std::vector<std::string> written_;
};

// True for the names a run writes in its output folder (trajectory.txt, summary.json, render_*.png,
// mesh*.ply, ...) and for the temporary files of an interrupted write.
bool isRunOutputName(const std::string& name);

}  // namespace voxfuse::app
