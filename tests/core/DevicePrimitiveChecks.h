#pragma once
// The launcher, primitives and atomics of a device type (CpuDevice, CudaDevice), each against a plain
// serial answer. Included by tests/core/CpuDeviceTest.cpp and tests/cuda/CudaDeviceTest.cu, so that
// both devices pass the same checks.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "core/DeviceScratch.h"
#include "voxfuse/core/Atomics.h"
#include "voxfuse/core/MemoryBlock.h"
#include "voxfuse/shared/NormalEquations.h"
#include "voxfuse/shared/RobustKernel.h"

namespace voxfuse::test {

template <class T>
MemoryBlock<T> blockOn(Device where, const std::vector<T>& values) {
    MemoryBlock<T> b(values.size(), where == Device::CPU, where == Device::CUDA);
    b.writeRange(where, 0, values.data(), values.size());
    return b;
}

template <class T>
std::vector<T> valuesOf(Device where, const MemoryBlock<T>& b, std::size_t count) {
    std::vector<T> v(count);
    b.readRange(where, 0, v.data(), count);
    return v;
}

// Loop bodies of the checks (functors, as the engines' are).
struct CountVisits {
    int* visits;
    VF_HOST_DEVICE void operator()(int i) const { atomicAddInt(&visits[i], 1); }
};
struct AddToOneCounter {
    int* counter;
    VF_HOST_DEVICE void operator()(int) const { atomicAddInt(counter, 1); }
};
struct ClaimSmallestIndex {
    int* claim;
    int buckets;
    VF_HOST_DEVICE void operator()(int i) const { atomicMinInt(&claim[i % buckets], i); }
};
struct FloatMinMax {
    const float* values;
    float* min_max;
    VF_HOST_DEVICE void operator()(int i) const {
        atomicMinFloat(&min_max[0], values[i]);
        atomicMaxFloat(&min_max[1], values[i]);
    }
};
// Element i claims slot i % slots for itself where the slot is still empty; wins[i] says whether it did.
struct ClaimEmptySlot {
    std::uint64_t* slots;
    int slot_count;
    int* wins;
    VF_HOST_DEVICE void operator()(int i) const {
        constexpr std::uint64_t kEmpty = ~std::uint64_t(0);
        const std::uint64_t mine = std::uint64_t(i) << 32 | 0x5a5aull;  // high bits used
        wins[i] = atomicCasU64(&slots[i % slot_count], kEmpty, mine) == kEmpty ? 1 : 0;
    }
};
struct IsMultipleOf {
    int k;
    VF_HOST_DEVICE bool operator()(int i) const { return i % k == 0; }
};

template <class TDevice>
void checkParallelForVisitsEveryElementOnce() {
    constexpr Device where = TDevice::kind;
    for (int n : {0, 1, 255, 256, 257, 100000}) {
        MemoryBlock<int> visits = blockOn(where, std::vector<int>(std::size_t(n) + 1, 0));
        TDevice::parallelFor(n, CountVisits{visits.data(where)});
        const std::vector<int> v = valuesOf(where, visits, std::size_t(n) + 1);
        for (int i = 0; i < n; ++i) ASSERT_EQ(v[std::size_t(i)], 1) << "element " << i << " of " << n;
        ASSERT_EQ(v[std::size_t(n)], 0) << "nothing beyond n";
    }
}

template <class TDevice>
void checkAtomicsCombineExactly() {
    constexpr Device where = TDevice::kind;
    const int n = 200000;
    MemoryBlock<int> counter = blockOn(where, std::vector<int>{0});
    TDevice::parallelFor(n, AddToOneCounter{counter.data(where)});
    EXPECT_EQ(valuesOf(where, counter, 1)[0], n);

    const int buckets = 97;
    MemoryBlock<int> claims = blockOn(where, std::vector<int>(buckets, 1 << 30));
    TDevice::parallelFor(n, ClaimSmallestIndex{claims.data(where), buckets});
    const std::vector<int> c = valuesOf(where, claims, buckets);
    for (int b = 0; b < buckets; ++b) ASSERT_EQ(c[std::size_t(b)], b);

    // Mixed signs: the GPU orders negative and positive floats through different integer atomics.
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-5.f, 5.f);
    std::vector<float> values(50000);
    for (float& v : values) v = u(rng);
    for (const std::vector<float>& start : {std::vector<float>{1e30f, -1e30f}, std::vector<float>{0.f, 0.f}}) {
        MemoryBlock<float> in = blockOn(where, values), min_max = blockOn(where, start);
        TDevice::parallelFor(int(values.size()), FloatMinMax{in.data(where), min_max.data(where)});
        const std::vector<float> r = valuesOf(where, min_max, 2);
        EXPECT_EQ(r[0], std::min(start[0], *std::min_element(values.begin(), values.end())));
        EXPECT_EQ(r[1], std::max(start[1], *std::max_element(values.begin(), values.end())));
    }

    // Signed zeros: -0 orders below +0 on both devices, so both keep the same bits. The reference
    // orders floats by the classic total-order key of their bits, independently of Atomics.h.
    auto order_key = [](float f) {
        std::uint32_t bits;
        std::memcpy(&bits, &f, sizeof bits);
        return (bits >> 31) ? ~bits : bits | 0x80000000u;
    };
    auto bits_of = [](float f) {
        std::uint32_t bits;
        std::memcpy(&bits, &f, sizeof bits);
        return bits;
    };
    const std::vector<std::vector<float>> value_sets = {{-0.f},       {0.f},       {-0.f, 0.f},     {0.f, -0.f, 0.f},
                                                        {-1.f, -0.f}, {1.f, -0.f}, {-0.f, 2.f, 0.f}};
    for (float start : {0.f, -0.f, -1.f, 1.f, 1e30f, -1e30f}) {
        for (const std::vector<float>& set : value_sets) {
            float expected_min = start, expected_max = start;
            for (float v : set) {
                if (order_key(v) < order_key(expected_min)) expected_min = v;
                if (order_key(v) > order_key(expected_max)) expected_max = v;
            }
            MemoryBlock<float> in = blockOn(where, set), min_max = blockOn(where, std::vector<float>{start, start});
            TDevice::parallelFor(int(set.size()), FloatMinMax{in.data(where), min_max.data(where)});
            const std::vector<float> r = valuesOf(where, min_max, 2);
            EXPECT_EQ(bits_of(r[0]), bits_of(expected_min))
                << "min from " << start << " over " << set.size() << " values, first " << set[0];
            EXPECT_EQ(bits_of(r[1]), bits_of(expected_max))
                << "max from " << start << " over " << set.size() << " values, first " << set[0];
        }
    }
}

// One claim per slot wins, and the slot holds the winner's value.
template <class TDevice>
void checkCompareAndSwapClaimsOncePerSlot() {
    constexpr Device where = TDevice::kind;
    const int n = 100000, slot_count = 211;
    MemoryBlock<std::uint64_t> slots = blockOn(where, std::vector<std::uint64_t>(slot_count, ~std::uint64_t(0)));
    MemoryBlock<int> wins = blockOn(where, std::vector<int>(n, -1));
    TDevice::parallelFor(n, ClaimEmptySlot{slots.data(where), slot_count, wins.data(where)});
    const std::vector<std::uint64_t> s = valuesOf(where, slots, slot_count);
    const std::vector<int> w = valuesOf(where, wins, n);
    std::vector<int> winners(slot_count, 0);
    for (int i = 0; i < n; ++i) {
        ASSERT_TRUE(w[std::size_t(i)] == 0 || w[std::size_t(i)] == 1);
        if (!w[std::size_t(i)]) continue;
        ++winners[std::size_t(i % slot_count)];
        EXPECT_EQ(s[std::size_t(i % slot_count)], std::uint64_t(i) << 32 | 0x5a5aull) << "the slot holds its winner";
    }
    for (int k = 0; k < slot_count; ++k) ASSERT_EQ(winners[std::size_t(k)], 1) << "slot " << k;
}

template <class TDevice>
void checkExclusiveScan() {
    constexpr Device where = TDevice::kind;
    DeviceScratch scratch(where);
    std::mt19937 rng(3);
    for (int n : {1, 7, 1000, 300000}) {
        std::vector<int> in(static_cast<std::size_t>(n));
        for (int& v : in) v = int(rng() % 5);
        MemoryBlock<int> a = blockOn(where, in), out(std::size_t(n), where == Device::CPU, where == Device::CUDA);
        const int total = TDevice::exclusiveScan(a.data(where), out.data(where), n, scratch);
        const std::vector<int> o = valuesOf(where, out, std::size_t(n));
        int sum = 0;
        for (int i = 0; i < n; ++i) {
            ASSERT_EQ(o[std::size_t(i)], sum) << "n " << n << " i " << i;
            sum += in[std::size_t(i)];
        }
        EXPECT_EQ(total, sum);
        // In place, as the removal's bucket counts are scanned.
        const int again = TDevice::exclusiveScan(a.data(where), a.data(where), n, scratch);
        EXPECT_EQ(again, sum);
        EXPECT_EQ(valuesOf(where, a, std::size_t(n)), o);
    }
}

template <class TDevice>
void checkSelectIndices() {
    constexpr Device where = TDevice::kind;
    DeviceScratch scratch(where);
    for (int n : {1, 5000, 1200000}) {
        MemoryBlock<int> out(std::size_t(n), where == Device::CPU, where == Device::CUDA);
        const int count = TDevice::selectIndices(n, IsMultipleOf{3}, out.data(where), scratch);
        ASSERT_EQ(count, (n + 2) / 3);
        const std::vector<int> o = valuesOf(where, out, std::size_t(count));
        for (int k = 0; k < count; ++k) ASSERT_EQ(o[std::size_t(k)], 3 * k) << "ascending and complete";
    }
    // Everything: the selection is the whole of `out`.
    {
        const int n = 1200000;
        MemoryBlock<int> out(std::size_t(n), where == Device::CPU, where == Device::CUDA);
        ASSERT_EQ(TDevice::selectIndices(n, IsMultipleOf{1}, out.data(where), scratch), n);
        const std::vector<int> o = valuesOf(where, out, std::size_t(n));
        for (int k = 0; k < n; ++k) ASSERT_EQ(o[std::size_t(k)], k);
    }
    // Sparse, as the visible or stored entries of a hash: most stretches of the range hold none. The
    // larger n is beyond the CPU's most shares (1024 of 4096 elements).
    for (int n : {1200000, 1024 * 4096 + 4097}) {
        MemoryBlock<int> out(std::size_t(n), where == Device::CPU, where == Device::CUDA);
        const int count = TDevice::selectIndices(n, IsMultipleOf{99991}, out.data(where), scratch);
        ASSERT_EQ(count, (n + 99990) / 99991);
        const std::vector<int> o = valuesOf(where, out, std::size_t(count));
        for (int k = 0; k < count; ++k) ASSERT_EQ(o[std::size_t(k)], 99991 * k) << "n " << n;
    }
}

template <class TDevice>
void checkSortUnique() {
    constexpr Device where = TDevice::kind;
    DeviceScratch scratch(where);
    std::mt19937_64 rng(11);
    for (int n : {1, 2, 1000, 500000}) {
        std::vector<std::uint64_t> keys(static_cast<std::size_t>(n));
        for (auto& k : keys) k = rng() % std::uint64_t(n / 3 + 1) * 0x100000001ull;  // many repeats, high bits used
        if (n > 2) keys[1] = ~std::uint64_t(0);                                      // the largest key sorts last
        MemoryBlock<std::uint64_t> b = blockOn(where, keys);
        const int count = TDevice::sortUnique(b.data(where), n, scratch);
        std::vector<std::uint64_t> expected = keys;
        std::sort(expected.begin(), expected.end());
        expected.erase(std::unique(expected.begin(), expected.end()), expected.end());
        ASSERT_EQ(count, int(expected.size()));
        EXPECT_EQ(valuesOf(where, b, std::size_t(count)), expected);
    }
}

struct AboveHalf {
    const float* values;
    VF_HOST_DEVICE bool operator()(int i) const { return values[i] > 0.5f; }
};
struct ValueAt {
    const float* values;
    VF_HOST_DEVICE float operator()(int i) const { return values[i]; }
};
// Term i: J = (1, x, x^2, ..., x^5) with x = values[i], r = values[i] - 0.5; none where x < 0.1.
struct PolynomialTerms {
    const float* values;
    VF_HOST_DEVICE bool operator()(int i, float J[6], float& r) const {
        const float x = values[i];
        if (x < 0.1f) return false;
        float p = 1.f;
        for (int k = 0; k < 6; ++k, p *= x) J[k] = p;
        r = x - 0.5f;
        return true;
    }
};

template <class TDevice>
void checkCountMaxAndNormalEquations() {
    constexpr Device where = TDevice::kind;
    DeviceScratch scratch(where);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (int n : {1, 1000, 307200}) {
        std::vector<float> values(static_cast<std::size_t>(n));
        for (float& v : values) v = u(rng);
        MemoryBlock<float> b = blockOn(where, values);
        const int above = int(std::count_if(values.begin(), values.end(), [](float v) { return v > 0.5f; }));
        EXPECT_EQ(TDevice::countIf(n, AboveHalf{b.data(where)}, scratch), above);
        EXPECT_EQ(TDevice::maxOf(n, ValueAt{b.data(where)}, -1.f, scratch),
                  *std::max_element(values.begin(), values.end()));
        EXPECT_EQ(TDevice::maxOf(n, ValueAt{b.data(where)}, 2.f, scratch), 2.f);

        // Against a serial sum in double: equal to double rounding; and the same bits run after run.
        NormalEquations<double> serial = NormalEquations<double>::zero();
        for (int i = 0; i < n; ++i) {
            float J[6], r;
            if (!PolynomialTerms{values.data()}(i, J, r)) continue;
            const float w = robustWeight(RobustKernel::Huber, r, 0.2f);
            if (w > 0.f) serial.addTerm(J, r, w);
        }
        const NormalEquations<double> a =
            TDevice::sumNormalEquations(n, PolynomialTerms{b.data(where)}, RobustKernel::Huber, 0.2f, scratch);
        const NormalEquations<double> again =
            TDevice::sumNormalEquations(n, PolynomialTerms{b.data(where)}, RobustKernel::Huber, 0.2f, scratch);
        EXPECT_EQ(a.count, serial.count);
        for (int k = 0; k < 21; ++k) {
            EXPECT_NEAR(a.hessian[k], serial.hessian[k], 1e-9 * std::max(1.0, std::fabs(serial.hessian[k])));
            EXPECT_EQ(a.hessian[k], again.hessian[k]) << "deterministic";
        }
        for (int k = 0; k < 6; ++k)
            EXPECT_NEAR(a.gradient[k], serial.gradient[k], 1e-9 * std::max(1.0, std::fabs(serial.gradient[k])));
        EXPECT_NEAR(a.weighted_cost, serial.weighted_cost, 1e-9 * std::max(1.0, serial.weighted_cost));
    }
}

template <class TDevice>
void checkReadAndWrite() {
    constexpr Device where = TDevice::kind;
    DeviceScratch scratch(where);
    struct Pair {
        int a;
        float b;
    };
    MemoryBlock<Pair> p(1, where == Device::CPU, where == Device::CUDA);
    TDevice::write(p.data(where), Pair{42, 2.5f});
    const Pair back = TDevice::read(p.data(where), scratch);
    EXPECT_EQ(back.a, 42);
    EXPECT_EQ(back.b, 2.5f);
}

}  // namespace voxfuse::test
