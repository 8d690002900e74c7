#pragma once
// What the fuzz targets share. The parsers read files, so each input is written to a file of the
// target's own (one per process, in $TMPDIR) with the extension the reader dispatches on. A target
// catches voxfuse::Error, the parsers' promised answer to bad input; anything else escapes and is
// reported by libFuzzer (or the corpus replay) as the bug it is.

#include <cstddef>
#include <cstdint>
#include <string>

namespace voxfuse::fuzz {

// Writes the input to this process's scratch file named `name` and returns its path.
std::string writeInput(const std::uint8_t* data, std::size_t size, const std::string& name);
// This process's scratch folder (created on first use).
std::string scratchFolder();

}  // namespace voxfuse::fuzz
