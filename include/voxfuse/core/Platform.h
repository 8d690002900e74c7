#pragma once
// Macros that let one function body compile under g++ (CPU layer) and nvcc (CUDA layer).

#if defined(__CUDACC__)
#define VF_HOST_DEVICE __host__ __device__
#define VF_DEVICE __device__
#else
#define VF_HOST_DEVICE
#define VF_DEVICE
#endif
