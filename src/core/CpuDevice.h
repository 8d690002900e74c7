#pragma once
// The CPU launcher and primitives: what a stage written once (src/engines/*_Impl.h) needs from the
// device it runs on. Its twin for the GPU is CudaDevice (CudaDevice.cuh); both offer the same static
// functions, so a stage is a template on the device type.
//
//   parallelFor(n, body)          body(i) for i in [0, n), any order, in parallel
//   parallelForTeams<Shared>(n, body)
//                                 body(team, i, shared) for i in [0, n), one team (core/Team.h) per i
//                                 with a `Shared` (trivially constructible) of its own
//   exclusiveScan(in, out, n)     out[i] = in[0] + ... + in[i - 1]; returns the total (int or long long)
//   selectIndices(n, pred, out)   the i in [0, n) with pred(i), ascending; returns how many
//   sortUnique(keys, n)           sorts 64-bit keys ascending and drops repeats; returns how many remain
//   countIf(n, pred)              how many i in [0, n) have pred(i)
//   maxOf(n, value, init)         the largest of init and value(i) over [0, n) (floats)
//   sumNormalEquations(n, terms, kernel, scale)
//                                 the 6x6 system of n Gauss-Newton terms (terms(i, J, r) false: none),
//                                 robustly weighted, summed in double in an order fixed by n alone
//   read(p, scratch), write(p, v) one element between the device's memory and the host
//
// Loop bodies are functors from include/voxfuse/shared/ with VF_HOST_DEVICE operator()(int). Every loop
// runs on the library's CPU threads (voxfuse/core/CpuThreads.h).

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <type_traits>
#include <vector>

#include "core/DeviceScratch.h"
#include "voxfuse/core/CpuThreads.h"
#include "voxfuse/core/Team.h"
#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/shared/NormalEquations.h"
#include "voxfuse/shared/RobustKernel.h"

namespace voxfuse {

// Element loops are compiled twice, for the x86-64 baseline and for AVX2, and the loader picks the one
// the CPU runs (GCC function multiversioning); `flatten` inlines the loop body and all it calls into
// each. AVX2 without FMA: a fused multiply-add rounds once where the baseline and the CUDA layer
// (-fmad=false) round twice, so every result keeps its bits on every CPU.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define VF_CPU_CLONES __attribute__((target_clones("avx2", "default"), flatten))
#else
#define VF_CPU_CLONES
#endif

namespace cpu_detail {

// body(i) for i in [begin, end), on a copy of the body: stores through the body's output pointers
// could alias the caller's body object, and the compiler would then reload every member after every
// store; they cannot alias a copy of the function's own.
template <class Body>
VF_CPU_CLONES void runElements(const Body& body, int begin, int end) {
    const Body local = body;
    for (int i = begin; i < end; ++i) local(i);
}

// The normal equations of terms [begin, end), in batches of kTermBatch: first each term and its
// robust weight, one at a time (a term may look up a model pixel or be rejected; a rejected or
// zero-weight term becomes zeros), then every product of the batch summed kTermLanes terms abreast
// into a lane sum per entry, the lanes added in order at the end. The lanes are written out, so the
// order of every addition is fixed by this code: the AVX2 clone and the baseline give the same bits.
// One term at a time, the 29 sums of each term were a chain of scalar double additions.
constexpr int kTermBatch = 64;
constexpr int kTermLanes = 4;
constexpr int kTermSums = 29;  // 21 Hessian entries, 6 gradient entries, the weighted cost, the squared sum

// lanes[l] += a[k] * b[k] for k = l (mod kTermLanes) over one batch, in order of k.
inline void addLaneProducts(double lanes[kTermLanes], const double* a, const double* b) {
    for (int k = 0; k < kTermBatch; k += kTermLanes)
        for (int l = 0; l < kTermLanes; ++l) lanes[l] += a[k + l] * b[k + l];
}

template <class Terms>
VF_CPU_CLONES NormalEquations<double> sumTermShare(const Terms& terms, RobustKernel kernel, float kernel_scale,
                                                   int begin, int end) {
    static_assert(kTermBatch % kTermLanes == 0, "a batch is whole lane groups");
    const Terms local = terms;  // see runElements
    double lanes[kTermSums][kTermLanes] = {};
    int count = 0;
    alignas(64) double J[6][kTermBatch], r[kTermBatch], w[kTermBatch], wj[kTermBatch];
    for (int batch = begin; batch < end; batch += kTermBatch) {
        const int m = std::min(kTermBatch, end - batch);
        for (int k = 0; k < kTermBatch; ++k) {
            float Jk[6] = {0.f, 0.f, 0.f, 0.f, 0.f, 0.f}, rk = 0.f, wk = 0.f;
            if (k < m && local(batch + k, Jk, rk)) wk = robustWeight(kernel, rk, kernel_scale);
            const bool used = wk > 0.f;
            count += used ? 1 : 0;
            w[k] = used ? double(wk) : 0.0;
            r[k] = used ? double(rk) : 0.0;
            for (int a = 0; a < 6; ++a) J[a][k] = used ? double(Jk[a]) : 0.0;  // zeros, not 0 * NaN
        }
        // The products and their order are addTerm's: (w J_a) J_b, (w J_a) r, (w r) r, r r.
        int entry = 0;
        for (int a = 0; a < 6; ++a) {
            for (int k = 0; k < kTermBatch; ++k) wj[k] = w[k] * J[a][k];
            for (int b = a; b < 6; ++b) addLaneProducts(lanes[entry++], wj, J[b]);
            addLaneProducts(lanes[21 + a], wj, r);
        }
        for (int k = 0; k < kTermBatch; ++k) wj[k] = w[k] * r[k];
        addLaneProducts(lanes[27], wj, r);
        addLaneProducts(lanes[28], r, r);
    }
    NormalEquations<double> sums = NormalEquations<double>::zero();
    for (int l = 0; l < kTermLanes; ++l) {
        for (int e = 0; e < 21; ++e) sums.hessian[e] += lanes[e][l];
        for (int a = 0; a < 6; ++a) sums.gradient[a] += lanes[21 + a][l];
        sums.weighted_cost += lanes[27][l];
        sums.squared_sum += lanes[28][l];
    }
    sums.count = count;
    return sums;
}

// A team's shared memory as the GPU hands it out: uninitialised. Filled with a byte pattern that no
// loop body reads as a meaningful value (ints about -8.4e8, floats about -4.3e8), so that a body
// reading shared memory it has not written gives wrong results on the CPU too, not zeros that happen
// to pass.
constexpr unsigned char kUnwrittenSharedByte = 0xCD;
template <class Shared>
void poisonShared(Shared& shared) {
    std::memset(static_cast<void*>(&shared), kUnwrittenSharedByte, sizeof(Shared));
}
template <class Shared>
std::unique_ptr<Shared> uninitialisedShared() {
    static_assert(std::is_trivially_default_constructible<Shared>::value && std::is_trivially_copyable<Shared>::value,
                  "team shared memory holds plain data, constructed by no one (as on the GPU)");
    std::unique_ptr<Shared> shared(new Shared);  // default-initialised: not zeroed
    poisonShared(*shared);
    return shared;
}

}  // namespace cpu_detail

struct CpuDevice {
    static constexpr Device kind = Device::CPU;
    // Loop bodies come in two launch shapes: a wide element (a row of pixels, a whole block) with a
    // cache for the CPU's few threads, or one item per element for the GPU's many. Stages pick theirs
    // from this, not from `kind`, so that a test can run the GPU's shapes on the CPU.
    static constexpr bool kOneThreadPerItem = false;

    // Dynamic scheduling in chunks of about 1/32 of a thread's share: loop bodies of uneven cost (rays,
    // pixels with and without depth) balance, and cheap ones pay one scheduling step per chunk.
    template <class Body>
    static void parallelFor(int n, const Body& body) {
        if (n <= 0) return;
        const int chunk = std::max(1, n / (32 * cpuThreadCount()));
        const int chunks = (n + chunk - 1) / chunk;
        forEachCpuTask(chunks,
                       [&](int c) { cpu_detail::runElements(body, c * chunk, std::min(n, c * chunk + chunk)); });
    }

    // A team is one thread; its shared memory is allocated once per task (one task per thread) and
    // reused for every item the task claims. It starts poisoned (uninitialisedShared), as the GPU's
    // starts undefined; the GPU-shaped test launcher poisons it before every item.
    template <class Shared, class Body>
    static void parallelForTeams(int n, const Body& body) {
        if (n <= 0) return;
        const int threads = cpuThreadCount();
        const int chunk = std::max(1, n / (32 * threads));
        std::atomic<int> next{0};
        forEachCpuTask(std::min(threads, (n + chunk - 1) / chunk), [&](int) {
            const std::unique_ptr<Shared> shared = cpu_detail::uninitialisedShared<Shared>();
            for (int begin = next.fetch_add(chunk); begin < n; begin = next.fetch_add(chunk))
                for (int i = begin; i < std::min(n, begin + chunk); ++i) body(Team{0, 1}, i, *shared);
        });
    }

    template <class T>
    static T exclusiveScan(const T* in, T* out, int n, DeviceScratch&) {
        T sum = 0;
        for (int i = 0; i < n; ++i) {
            const T v = in[i];
            out[i] = sum;
            sum += v;
        }
        return sum;
    }

    // Two passes over equal shares of at least 4096 elements: count per share, then write each share
    // that has any at its offset. Many small shares make sparse selections (the visible or stored few
    // of a million hash entries) skip most of the second pass.
    template <class Pred>
    static int selectIndices(int n, const Pred& pred, int* out, DeviceScratch&) {
        if (n <= 0) return 0;
        constexpr int kMaxShares = 1024;
        const int shares = std::max(1, std::min(kMaxShares, n / 4096));
        std::vector<int> counts(static_cast<std::size_t>(shares) + 1, 0);
        auto share_begin = [&](int s) { return int((long long)n * s / shares); };
        // Each share's bounds in locals: the stores through `o` may alias anything the lambda reads
        // by reference, which made the loop recompute its bound (a 64-bit division) per element.
        forEachCpuTask(shares, [&](int s) {
            const int begin = share_begin(s), end = share_begin(s + 1);
            int c = 0;
            for (int i = begin; i < end; ++i) c += pred(i) ? 1 : 0;
            counts[std::size_t(s) + 1] = c;
        });
        for (int s = 0; s < shares; ++s) counts[std::size_t(s) + 1] += counts[std::size_t(s)];
        forEachCpuTask(shares, [&](int s) {
            if (counts[std::size_t(s) + 1] == counts[std::size_t(s)]) return;
            const int begin = share_begin(s), end = share_begin(s + 1);
            int* o = out + counts[std::size_t(s)];
            for (int i = begin; i < end; ++i)
                if (pred(i)) *o++ = i;
        });
        return counts.back();
    }

    static int sortUnique(std::uint64_t* keys, int n, DeviceScratch&) {
        std::sort(keys, keys + n);
        return int(std::unique(keys, keys + n) - keys);
    }

    // Counted per share of the elements (forEachCpuShare), the shares' counts added as they finish.
    template <class Pred>
    static int countIf(int n, const Pred& pred, DeviceScratch&) {
        std::atomic<int> count{0};
        forEachCpuShare(std::size_t(std::max(n, 0)), 4096, [&](std::size_t begin, std::size_t end) {
            int c = 0;
            for (int i = int(begin); i < int(end); ++i) c += pred(i) ? 1 : 0;
            count.fetch_add(c, std::memory_order_relaxed);
        });
        return count.load();
    }

    // The same for the largest value: the maximum does not depend on the order it is taken in.
    template <class Value>
    static float maxOf(int n, const Value& value, float init, DeviceScratch&) {
        std::mutex m;
        float best = init;
        forEachCpuShare(std::size_t(std::max(n, 0)), 4096, [&](std::size_t begin, std::size_t end) {
            float share_best = init;
            for (int i = int(begin); i < int(end); ++i) share_best = std::max(share_best, value(i));
            const std::lock_guard<std::mutex> lock(m);
            best = std::max(best, share_best);
        });
        return best;
    }

    // Partial sums over fixed shares of the terms, taken by whichever thread is free and added in share
    // order: the result depends on n alone (not on the thread count or on which thread finished first,
    // as a reduction in completion order would), and threads do not wait on the one whose static half
    // held more of the image's valid pixels.
    template <class Terms>
    static NormalEquations<double> sumNormalEquations(int n, const Terms& terms, RobustKernel kernel,
                                                      float kernel_scale, DeviceScratch&) {
        constexpr int kMaxShares = 64;
        constexpr int kMinShareTerms = 1024;
        const int shares = std::max(1, std::min(kMaxShares, n / kMinShareTerms));
        std::vector<NormalEquations<double>> partials(static_cast<std::size_t>(shares));
        forEachCpuTask(shares, [&](int s) {
            const int begin = int((long long)n * s / shares), end = int((long long)n * (s + 1) / shares);
            partials[std::size_t(s)] = cpu_detail::sumTermShare(terms, kernel, kernel_scale, begin, end);
        });
        NormalEquations<double> total = NormalEquations<double>::zero();
        for (const NormalEquations<double>& p : partials) total.add(p);
        return total;
    }

    template <class T>
    static T read(const T* p, DeviceScratch&) {
        return *p;
    }
    template <class T>
    static void write(T* p, const T& value) {
        *p = value;
    }
};

}  // namespace voxfuse
