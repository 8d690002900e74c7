#pragma once
// Macros that let one function body compile under g++ (CPU layer) and nvcc (CUDA layer).

#if defined(__CUDACC__)
#define VF_HOST_DEVICE __host__ __device__
#define VF_DEVICE __device__
#else
#define VF_HOST_DEVICE
#define VF_DEVICE
#endif

// Hints that the CPU will soon read, or write, the cache line holding p. No-ops in device code, where
// the GPU's many threads in flight hide memory latency instead.
#if defined(__CUDA_ARCH__)
#define VF_PREFETCH_FOR_READ(p) ((void)(p))
#define VF_PREFETCH_FOR_WRITE(p) ((void)(p))
#else
#define VF_PREFETCH_FOR_READ(p) __builtin_prefetch((p), 0, 3)
#define VF_PREFETCH_FOR_WRITE(p) __builtin_prefetch((p), 1, 3)
#endif
