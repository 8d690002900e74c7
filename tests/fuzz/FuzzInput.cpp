#include "FuzzInput.h"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace voxfuse::fuzz {

std::string scratchFolder() {
    static const std::string folder = [] {
        const char* tmp = std::getenv("TMPDIR");
        const std::filesystem::path p = std::filesystem::path(tmp && *tmp ? tmp : "/tmp") / ("voxfuse_fuzz_" + std::to_string(::getpid()));
        std::filesystem::create_directories(p);
        return p.string();
    }();
    return folder;
}

std::string writeInput(const std::uint8_t* data, std::size_t size, const std::string& name) {
    const std::string path = scratchFolder() + "/" + name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    if (!out.flush()) throw std::runtime_error("fuzz harness: cannot write " + path);
    return path;
}

}  // namespace voxfuse::fuzz
