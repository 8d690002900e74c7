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
    while (value < current && !__atomic_compare_exchange_n(target, &current, value, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
    }
    return current;
#endif
}

// *target = min(*target, value) and max, for floats that are not NaN.
VF_HOST_DEVICE inline void atomicMinFloat(float* target, float value) {
#if defined(__CUDA_ARCH__)
    // IEEE floats of one sign order like their bit patterns (as signed ints for positives, reversed
    // as unsigned ints for negatives).
    if (value >= 0.f) atomicMin(reinterpret_cast<int*>(target), __float_as_int(value));
    else atomicMax(reinterpret_cast<unsigned*>(target), __float_as_uint(value));
#else
    float current;
    __atomic_load(target, &current, __ATOMIC_RELAXED);
    while (value < current && !__atomic_compare_exchange(target, &current, &value, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
    }
#endif
}

VF_HOST_DEVICE inline void atomicMaxFloat(float* target, float value) {
#if defined(__CUDA_ARCH__)
    if (value >= 0.f) atomicMax(reinterpret_cast<int*>(target), __float_as_int(value));
    else atomicMin(reinterpret_cast<unsigned*>(target), __float_as_uint(value));
#else
    float current;
    __atomic_load(target, &current, __ATOMIC_RELAXED);
    while (value > current && !__atomic_compare_exchange(target, &current, &value, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
    }
#endif
}

// A store that other threads may race with, where every racing writer stores a complete valid value
// and any of them may win (the report's "only the most recently written" marks). Relaxed atomic on
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
