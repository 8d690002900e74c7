#include "HeapPolicy.h"

#include <cstdlib>  // defines __GLIBC__ where the C library is glibc
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace voxfuse::app {

// glibc maps blocks of 128 KiB and more on their own, but once it unmaps one it raises that limit to
// the block's size (up to 32 MiB) and the limit above which it returns the heap's free top to the
// system to twice that. A map's start-up allocations of tens of megabytes raise both, and from then
// on the heap keeps what it frees. Teddy played to and fro for 1140 frames (`voxfuse`, a render
// written every 25 frames) peaked at 346-349 MB, against 298 MB without the renders, with the live heap
// flat (heaptrack); with the limits fixed it peaks at 299 MB. Setting them turns the adjustment off.
// No frame makes a block this large (sources decode into reused images), so the fixed limits cost no
// time (teddy 1.000x side by side, meshing unchanged).
void useLongRunHeapPolicy() {
#if defined(__GLIBC__)
    mallopt(M_MMAP_THRESHOLD, 128 * 1024);
    mallopt(M_TRIM_THRESHOLD, 128 * 1024);
#endif
}

}  // namespace voxfuse::app
