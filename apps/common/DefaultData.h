#pragma once
// The sequence the front-ends run on when no SOURCE is given: the bundled synthetic room.

#include <string>

namespace voxfuse::app {

// The bundled room's folder: where `cmake --install` (or the .deb) put it, share/voxfuse/synthetic_room
// beside the program's bin/, else beside the sources of a build tree, else data/synthetic_room in the
// working folder. IoError naming `program` when none holds it.
std::string bundledSequence(const char* program);

}  // namespace voxfuse::app
