#pragma once
// The CUDA launcher and primitives: the same static functions as CpuDevice (CpuDevice.h, which says
// what each does), as kernel launches and CUB calls. Work is queued on the default stream in order;
// read() and the primitives that return a count wait for the GPU, the others return at once.
// Only nvcc compiles this file.

#include <cub/block/block_reduce.cuh>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_reduce.cuh>
#include <cub/device/device_scan.cuh>
#include <cub/device/device_select.cuh>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/iterator/transform_iterator.h>

#include <vector>

#include <cstdint>

#include "core/CudaCheck.h"
#include "core/DeviceScratch.h"
#include "voxfuse/core/Team.h"
#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/shared/NormalEquations.h"
#include "voxfuse/shared/RobustKernel.h"

namespace voxfuse {
namespace cuda_detail {

template <class Body>
__global__ void parallelForKernel(int n, Body body) {
    const int i = int(blockIdx.x * blockDim.x + threadIdx.x);
    if (i < n) body(i);
}

// One thread block per item; its `Shared` lives in the block's shared memory.
template <class Shared, class Body>
__global__ void parallelForTeamsKernel(Body body) {
    __shared__ Shared shared;
    body(Team{int(threadIdx.x), int(blockDim.x)}, int(blockIdx.x), shared);
}

inline std::size_t alignUp(std::size_t bytes) { return (bytes + 255) & ~std::size_t(255); }

// countIf and maxOf read their functor through these.
template <class Pred>
struct PredicateAsInt {
    Pred pred;
    __host__ __device__ int operator()(int i) const { return pred(i) ? 1 : 0; }
};
struct MaxFloat {
    __host__ __device__ float operator()(float a, float b) const { return a > b ? a : b; }
};

// The normal equations' reduction: a fixed grid of kNormalEquationBlocks blocks, each thread summing
// a fixed stride of terms in double, a block reduction, one partial per block; the host adds the
// partials in block order. The order of every addition is fixed by n: runs repeat to the bit.
constexpr int kNormalEquationThreads = 128;
constexpr int kNormalEquationBlocks = 264;  // two per multiprocessor of an H100/H200

struct AddNormalEquations {
    __device__ NormalEquations<double> operator()(const NormalEquations<double>& a,
                                                  const NormalEquations<double>& b) const {
        NormalEquations<double> s = a;
        s.add(b);
        return s;
    }
};

template <class Terms>
__global__ void __launch_bounds__(kNormalEquationThreads)
    sumNormalEquationsKernel(int n, Terms terms, RobustKernel kernel, float kernel_scale,
                             NormalEquations<double>* partials) {
    using BlockReduce = cub::BlockReduce<NormalEquations<double>, kNormalEquationThreads>;
    __shared__ typename BlockReduce::TempStorage temp;
    NormalEquations<double> local = NormalEquations<double>::zero();
    for (int i = int(blockIdx.x * blockDim.x + threadIdx.x); i < n; i += int(gridDim.x * blockDim.x)) {
        float J[6], r;
        if (!terms(i, J, r)) continue;
        const float w = robustWeight(kernel, r, kernel_scale);
        if (w > 0.f) local.addTerm(J, r, w);
    }
    const NormalEquations<double> block = BlockReduce(temp).Reduce(local, AddNormalEquations());
    if (threadIdx.x == 0) partials[blockIdx.x] = block;
}

}  // namespace cuda_detail

struct CudaDevice {
    static constexpr Device kind = Device::CUDA;
    static constexpr bool kOneThreadPerItem = true;
    static constexpr int kThreadsPerBlock = 256;

    template <class Body>
    static void parallelFor(int n, const Body& body) {
        if (n <= 0) return;
        cuda_detail::parallelForKernel<<<unsigned((n + kThreadsPerBlock - 1) / kThreadsPerBlock), kThreadsPerBlock>>>(
            n, body);
        VF_CUDA_CHECK_LAUNCH_OF(Body);
    }

    // Teams of kThreadsPerTeam threads: enough to hide memory latency while a block of shared memory of
    // up to ~16 KB per team still lets a multiprocessor hold a dozen teams.
    static constexpr int kThreadsPerTeam = 128;

    template <class Shared, class Body>
    static void parallelForTeams(int n, const Body& body) {
        static_assert(sizeof(Shared) <= 48 * 1024, "a team's shared memory must fit the static 48 KB");
        if (n <= 0) return;
        cuda_detail::parallelForTeamsKernel<Shared><<<unsigned(n), kThreadsPerTeam>>>(body);
        VF_CUDA_CHECK_LAUNCH_OF(Body);
    }

    template <class T>
    static T exclusiveScan(const T* in, T* out, int n, DeviceScratch& scratch) {
        if (n <= 0) return 0;
        // The total is the last offset plus the last input, read before an in-place scan overwrites it.
        T* last = static_cast<T*>(scratch.hostResult(2 * sizeof(T)));
        VF_CUDA_CHECK(cudaMemcpy(last + 1, in + n - 1, sizeof(T), cudaMemcpyDeviceToHost));
        std::size_t temp_bytes = 0;
        VF_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(nullptr, temp_bytes, in, out, n));
        void* temp = scratch.get(temp_bytes);
        VF_CUDA_CHECK(cub::DeviceScan::ExclusiveSum(temp, temp_bytes, in, out, n));
        VF_CUDA_CHECK(cudaMemcpy(last, out + n - 1, sizeof(T), cudaMemcpyDeviceToHost));
        return last[0] + last[1];
    }

    template <class Pred>
    static int selectIndices(int n, const Pred& pred, int* out, DeviceScratch& scratch) {
        if (n <= 0) return 0;
        const thrust::counting_iterator<int> first(0);
        std::size_t temp_bytes = 0;
        VF_CUDA_CHECK(cub::DeviceSelect::If(nullptr, temp_bytes, first, out, static_cast<int*>(nullptr), n, pred));
        char* base = static_cast<char*>(scratch.get(cuda_detail::alignUp(sizeof(int)) + temp_bytes));
        int* selected = reinterpret_cast<int*>(base);
        VF_CUDA_CHECK(
            cub::DeviceSelect::If(base + cuda_detail::alignUp(sizeof(int)), temp_bytes, first, out, selected, n, pred));
        return read(selected, scratch);
    }

    // Radix sort into a second buffer, then the unique keys back into `keys`.
    static int sortUnique(std::uint64_t* keys, int n, DeviceScratch& scratch) {
        if (n <= 1) return n;
        const std::size_t keys_bytes = cuda_detail::alignUp(std::size_t(n) * sizeof(std::uint64_t));
        std::size_t sort_bytes = 0, unique_bytes = 0;
        VF_CUDA_CHECK(cub::DeviceRadixSort::SortKeys(nullptr, sort_bytes, keys, keys, n));
        VF_CUDA_CHECK(cub::DeviceSelect::Unique(nullptr, unique_bytes, keys, keys, static_cast<int*>(nullptr), n));
        const std::size_t temp_bytes = sort_bytes > unique_bytes ? sort_bytes : unique_bytes;
        char* base = static_cast<char*>(scratch.get(keys_bytes + cuda_detail::alignUp(sizeof(int)) + temp_bytes));
        auto* sorted = reinterpret_cast<std::uint64_t*>(base);
        int* count = reinterpret_cast<int*>(base + keys_bytes);
        void* temp = base + keys_bytes + cuda_detail::alignUp(sizeof(int));
        VF_CUDA_CHECK(cub::DeviceRadixSort::SortKeys(temp, sort_bytes, keys, sorted, n));
        VF_CUDA_CHECK(cub::DeviceSelect::Unique(temp, unique_bytes, sorted, keys, count, n));
        return read(count, scratch);
    }

    template <class Pred>
    static int countIf(int n, const Pred& pred, DeviceScratch& scratch) {
        if (n <= 0) return 0;
        const auto values =
            thrust::make_transform_iterator(thrust::counting_iterator<int>(0), cuda_detail::PredicateAsInt<Pred>{pred});
        std::size_t temp_bytes = 0;
        VF_CUDA_CHECK(cub::DeviceReduce::Sum(nullptr, temp_bytes, values, static_cast<int*>(nullptr), n));
        char* base = static_cast<char*>(scratch.get(cuda_detail::alignUp(sizeof(int)) + temp_bytes));
        int* total = reinterpret_cast<int*>(base);
        VF_CUDA_CHECK(cub::DeviceReduce::Sum(base + cuda_detail::alignUp(sizeof(int)), temp_bytes, values, total, n));
        return read(total, scratch);
    }

    template <class Value>
    static float maxOf(int n, const Value& value, float init, DeviceScratch& scratch) {
        if (n <= 0) return init;
        const auto values = thrust::make_transform_iterator(thrust::counting_iterator<int>(0), value);
        std::size_t temp_bytes = 0;
        VF_CUDA_CHECK(cub::DeviceReduce::Reduce(nullptr, temp_bytes, values, static_cast<float*>(nullptr), n,
                                                cuda_detail::MaxFloat(), init));
        char* base = static_cast<char*>(scratch.get(cuda_detail::alignUp(sizeof(float)) + temp_bytes));
        float* best = reinterpret_cast<float*>(base);
        VF_CUDA_CHECK(cub::DeviceReduce::Reduce(base + cuda_detail::alignUp(sizeof(float)), temp_bytes, values, best, n,
                                                cuda_detail::MaxFloat(), init));
        return read(best, scratch);
    }

    template <class Terms>
    static NormalEquations<double> sumNormalEquations(int n, const Terms& terms, RobustKernel kernel,
                                                      float kernel_scale, DeviceScratch& scratch) {
        using cuda_detail::kNormalEquationBlocks;
        auto* partials =
            static_cast<NormalEquations<double>*>(scratch.get(sizeof(NormalEquations<double>) * kNormalEquationBlocks));
        cuda_detail::sumNormalEquationsKernel<<<kNormalEquationBlocks, cuda_detail::kNormalEquationThreads>>>(
            n, terms, kernel, kernel_scale, partials);
        VF_CUDA_CHECK_LAUNCH_OF(Terms);
        auto* host = static_cast<NormalEquations<double>*>(
            scratch.hostResult(sizeof(NormalEquations<double>) * kNormalEquationBlocks));
        VF_CUDA_CHECK(cudaMemcpy(host, partials, sizeof(NormalEquations<double>) * kNormalEquationBlocks,
                                 cudaMemcpyDeviceToHost));
        NormalEquations<double> total = NormalEquations<double>::zero();
        for (int b = 0; b < kNormalEquationBlocks; ++b) total.add(host[b]);
        return total;
    }

    // One element to the host through the scratch's pinned memory (waits for the GPU).
    template <class T>
    static T read(const T* p, DeviceScratch& scratch) {
        T* staged = static_cast<T*>(scratch.hostResult(sizeof(T)));
        VF_CUDA_CHECK(cudaMemcpy(staged, p, sizeof(T), cudaMemcpyDeviceToHost));
        return *staged;
    }
    template <class T>
    static void write(T* p, const T& value) {
        VF_CUDA_CHECK(cudaMemcpy(p, &value, sizeof(T), cudaMemcpyHostToDevice));
    }
};

}  // namespace voxfuse
