#pragma once
// The atomic operations loop bodies in shared/ use, one name for both devices: CUDA's atomic
// intrinsics in device code, GCC/Clang __atomic builtins on the CPU. All are relaxed: loop bodies use
// them to combine results (counts, minima, claims), never to order other memory accesses; a stage
// boundary (the end of a parallel loop or kernel) orders everything.

#include <cstdint>

#include "voxfuse/core/Platform.h"

namespace voxfuse {

// Adds `value` to *target; returns the previous value.
VF_HOST_DEVICE inline int atomicAddInt(int* target, int value) {
#if defined(__CUDA_ARCH__)
    return atomicAdd(target, value);
#else
    return __atomic_fetch_add(target, value, __ATOMIC_RELAXED);
#endif
}

// *target = min(*target, value); returns the previous value.
VF_HOST_DEVICE inline int atomicMinInt(int* target, int value) {
#if defined(__CUDA_ARCH__)
    return atomicMin(target, value);
#else
    int current = __atomic_load_n(target, __ATOMIC_RELAXED);
    while (value < current &&
           !__atomic_compare_exchange_n(target, &current, value, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
    }
    return current;
#endif
}

// Float minima and maxima order -0.0f below +0.0f, on both devices (a plain `<` calls them equal), so
// that both devices keep the same bits. Floats that are not NaN only.
VF_HOST_DEVICE inline bool floatSignBit(float v) {
#if defined(__CUDA_ARCH__)
    return (__float_as_uint(v) >> 31) != 0u;
#else
    return __builtin_signbit(v) != 0;
#endif
}
// a < b in that order: as by value, and -0 < +0.
VF_HOST_DEVICE inline bool floatOrderedBefore(float a, float b) {
    return a < b || (a == b && floatSignBit(a) && !floatSignBit(b));
}

// *target = min(*target, value) and max, in the order above.
VF_HOST_DEVICE inline void atomicMinFloat(float* target, float value) {
#if defined(__CUDA_ARCH__)
    // Floats whose sign bit is clear order like their bits as signed ints; floats whose sign bit is set
    // order in reverse of their bits as unsigned ints, and below every float without it. The branch is
    // on the sign bit, not on value >= 0, which -0.0f passes while its bits (as a signed int, INT_MIN)
    // order below every negative float's.
    if (!floatSignBit(value))
        atomicMin(reinterpret_cast<int*>(target), __float_as_int(value));
    else
        atomicMax(reinterpret_cast<unsigned*>(target), __float_as_uint(value));
#else
    float current;
    __atomic_load(target, &current, __ATOMIC_RELAXED);
    while (floatOrderedBefore(value, current) &&
           !__atomic_compare_exchange(target, &current, &value, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
    }
#endif
}

VF_HOST_DEVICE inline void atomicMaxFloat(float* target, float value) {
#if defined(__CUDA_ARCH__)
    if (!floatSignBit(value))
        atomicMax(reinterpret_cast<int*>(target), __float_as_int(value));
    else
        atomicMin(reinterpret_cast<unsigned*>(target), __float_as_uint(value));
#else
    float current;
    __atomic_load(target, &current, __ATOMIC_RELAXED);
    while (floatOrderedBefore(current, value) &&
           !__atomic_compare_exchange(target, &current, &value, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
    }
#endif
}

// Compare-and-swap of a 64-bit word: *target = desired where it held `expected`; returns what it held.
VF_HOST_DEVICE inline std::uint64_t atomicCasU64(std::uint64_t* target, std::uint64_t expected, std::uint64_t desired) {
#if defined(__CUDA_ARCH__)
    static_assert(sizeof(unsigned long long) == sizeof(std::uint64_t), "64-bit CAS");
    return std::uint64_t(atomicCAS(reinterpret_cast<unsigned long long*>(target), (unsigned long long)expected,
                                   (unsigned long long)desired));
#else
    __atomic_compare_exchange_n(target, &expected, desired, false, __ATOMIC_RELAXED, __ATOMIC_RELAXED);
    return expected;  // on failure the value found; on success the value replaced, which was `expected`
#endif
}

// A store that other threads may race with, where every racing writer stores a complete valid value
// and any of them may win (the InfiniTAM report's "only the most recently written" marks). Relaxed atomic on
// the CPU so that the race is defined C++; a plain store on the GPU, where aligned stores are atomic.
template <class T>
VF_HOST_DEVICE inline void racingStore(T* target, T value) {
#if defined(__CUDA_ARCH__)
    *target = value;
#else
    __atomic_store_n(target, value, __ATOMIC_RELAXED);
#endif
}

// A load of a value other threads may be changing (a counter polled to stop early): any value it
// held recently. Relaxed atomic on the CPU; a volatile load on the GPU, so that it is re-read.
template <class T>
VF_HOST_DEVICE inline T racingLoad(const T* target) {
#if defined(__CUDA_ARCH__)
    return *static_cast<const volatile T*>(target);
#else
    return __atomic_load_n(target, __ATOMIC_RELAXED);
#endif
}

}  // namespace voxfuse
