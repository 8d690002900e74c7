#pragma once
// How every front-end's main() ends: the program's work runs inside runReportingErrors, which turns
// whatever escapes it into one line on stderr and an exit status, never an abort.

#include <functional>

namespace voxfuse::app {

// Runs `body` and returns its exit status. What it throws becomes "PROGRAM: error: ..." and status 2
// (voxfuse::Error: bad input or settings; std::bad_alloc: more memory than there is, with a hint),
// or "PROGRAM: unexpected error: ..." and status 3 (any other exception).
int runReportingErrors(const char* program, const std::function<int()>& body);

}  // namespace voxfuse::app
