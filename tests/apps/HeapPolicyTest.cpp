// The front-ends' heap policy (apps/common/HeapPolicy.h): image-sized blocks stay out of the heap even
// after a larger block was freed, which without it raises glibc's mapping limit to that block's size.

#include "HeapPolicy.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace {

// Writes through a pointer the compiler cannot see through, so that it keeps each malloc and free.
void touch(void* p, std::size_t bytes) {
    static void* (*volatile set)(void*, int, std::size_t) = std::memset;
    set(p, 1, bytes);
}

}  // namespace

TEST(HeapPolicy, ImageSizedBlocksAreMappedEvenAfterALargerOneWasFreed) {
#if !defined(__GLIBC__) || defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
    GTEST_SKIP() << "the policy concerns glibc's allocator (a sanitizer replaces it)";
#else
    voxfuse::app::useLongRunHeapPolicy();
    // Mapped, and unmapped by free(): glibc's default would now raise its limit to 16 MiB (it does for
    // blocks up to 32 MiB).
    void* map_sized = std::malloc(std::size_t(16) << 20);
    ASSERT_NE(map_sized, nullptr);
    touch(map_sized, 4096);
    std::free(map_sized);
    const std::size_t mapped_before = mallinfo2().hblks;
    void* image = std::malloc(std::size_t(1) << 20);  // a 640x480 float image is 1.2 MB
    ASSERT_NE(image, nullptr);
    touch(image, 4096);
    EXPECT_EQ(mallinfo2().hblks, mapped_before + 1) << "the block came from the heap";
    std::free(image);
#endif
}
