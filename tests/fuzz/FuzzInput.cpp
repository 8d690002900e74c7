#include "FuzzInput.h"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace voxfuse::fuzz {

namespace {
// The process's own folder, removed when the process exits normally (a crash keeps its inputs).
struct ScratchFolder {
    std::filesystem::path path;
    ScratchFolder() {
        const char* tmp = std::getenv("TMPDIR");
        path = std::filesystem::path(tmp && *tmp ? tmp : "/tmp") / ("voxfuse_fuzz_" + std::to_string(::getpid()));
        std::filesystem::create_directories(path);
    }
    ~ScratchFolder() {
        std::error_code ignored;
        std::filesystem::remove_all(path, ignored);
    }
};
}  // namespace

std::string scratchFolder() {
    static const ScratchFolder folder;
    return folder.path.string();
}

std::string writeInput(const std::uint8_t* data, std::size_t size, const std::string& name) {
    const std::string path = scratchFolder() + "/" + name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    if (!out.flush()) throw std::runtime_error("fuzz harness: cannot write " + path);
    return path;
}

}  // namespace voxfuse::fuzz
