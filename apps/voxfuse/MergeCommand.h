#pragma once
// `voxfuse merge A.vfm B.vfm [...] --out C.vfm`: maps of the same place, made separately, joined into
// one map of submaps (MainEngine::mergeMap).

namespace voxfuse::app {

// argv[0] is "merge". Returns the exit status (0 merged, 2 refused: the error says why).
int runMergeCommand(int argc, char** argv);

}  // namespace voxfuse::app
