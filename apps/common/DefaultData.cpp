#include "DefaultData.h"

#include <filesystem>
#include <system_error>
#include <vector>

#include "voxfuse/core/Error.h"

namespace fs = std::filesystem;

namespace voxfuse::app {

std::string bundledSequence(const char* program) {
    // An installed program's own copy first: the source tree it was built from may be another version's.
    std::vector<fs::path> candidates;
    std::error_code ec;
    const fs::path self = fs::read_symlink("/proc/self/exe", ec);  // the program, wherever it was installed
    if (!ec) candidates.push_back(self.parent_path().parent_path() / "share" / "voxfuse" / "synthetic_room");
    candidates.push_back(VOXFUSE_SOURCE_DATA_DIR);
    candidates.push_back("data/synthetic_room");
    for (const fs::path& candidate : candidates)
        if (fs::exists(candidate / "rgb.txt", ec)) return candidate.string();
    throw IoError(VOXFUSE_SOURCE_DATA_DIR,
                  std::string("the bundled sequence is missing (not beside the sources, nor installed beside ") +
                      program + "): give a SOURCE (see " + program + " --help)");
}

}  // namespace voxfuse::app
