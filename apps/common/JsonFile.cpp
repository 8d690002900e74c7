#include "JsonFile.h"

#include "voxfuse/io/AtomicFile.h"

namespace voxfuse::app {

void writeJsonFile(const std::string& path, const Json& json) {
    const std::string text = json.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
    AtomicFile file(path);
    file.stream().write(text.data(), std::streamsize(text.size()));
    file.commit();
}

}  // namespace voxfuse::app
