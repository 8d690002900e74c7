#pragma once
// The C library's heap policy of the front-ends, for runs of any length (see HeapPolicy.cpp).

namespace voxfuse::app {

// Blocks of 128 KiB and more are mapped and unmapped on their own, and free memory above 128 KiB at
// the heap's top goes back to the system, however long the run. Call at the start of main(); does
// nothing outside glibc.
void useLongRunHeapPolicy();

}  // namespace voxfuse::app
