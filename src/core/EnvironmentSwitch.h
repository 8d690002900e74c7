#pragma once
// An on/off switch read from the environment: "1" is on; unset, empty or "0" is off. Anything else is
// reported once on stderr, naming the variable and its value, and counts as off (as the thread-count
// variables do, src/core/CpuThreads.cpp): a debugging switch never stops a run.

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace voxfuse {

// The switch's value for `text` (the variable's contents, nullptr when unset); `report` is called
// with the message for a value that is neither.
template <class Report>
bool switchFromText(const char* name, const char* text, Report&& report) {
    if (text == nullptr || *text == '\0' || std::strcmp(text, "0") == 0) return false;
    if (std::strcmp(text, "1") == 0) return true;
    report(std::string("voxfuse: ignoring ") + name + "=\"" + text + "\": not 0 or 1");
    return false;
}

inline bool switchFromEnvironment(const char* name) {
    return switchFromText(name, std::getenv(name),
                          [](const std::string& message) { std::fprintf(stderr, "%s\n", message.c_str()); });
}

}  // namespace voxfuse
