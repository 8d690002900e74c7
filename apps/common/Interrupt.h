#pragma once
// Ctrl-C (SIGINT) and SIGTERM ask a run to stop after the frame in progress, so that it still writes
// its outputs for the frames done; a second one ends the process at once (exit status 128 + signal).

namespace voxfuse::app::interrupt {

// Installs the handlers; `program` starts the line printed when a signal arrives.
void install(const char* program);
// True once a signal has asked the run to stop.
bool requested();
// The exit status of a run stopped by a signal (130 for SIGINT, 143 for SIGTERM), 0 if none came.
int exitStatus();

}  // namespace voxfuse::app::interrupt
