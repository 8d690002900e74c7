// Tracker settings files ("key = value" lines): parsed into settings the trackers accept, or refused.

#include "FuzzInput.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/TrackerSettings.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace voxfuse;
    try {
        const TrackerSettings s =
            parseTrackerSettings(std::string(reinterpret_cast<const char*>(data), size), "fuzz.txt");
        validateTrackerSettings(s);  // what the parser returns must be valid (this throws only on a parser bug)
    } catch (const ParseError&) {
    }
    return 0;
}
