#pragma once
// Fusing one observed semantic class into a voxel's class (the TUM KinectFusion report, section 3.6;
// see docs/DESIGN_NOTES.md), shared by the CPU loop and the CUDA kernel through integrateVoxel().
//
// A voxel keeps one class and a weight that counts the observations that agreed with it. An
// observation of the same class adds one. An observation of another class:
//  - Probabilistic (that report's rule, the default): the voxel takes the new class with probability
//    w_new / (w_old + w_new), w_new = 1, and then starts counting again from 1; otherwise nothing
//    changes. A voxel seen as class A for n_A frames in a row and then as B for n_B frames keeps A
//    with probability (n_A / (n_A + 1))^n_B: a long-held class is hard to dislodge, but a minority
//    class seen last still wins some voxels (about 1 - e^-1 of them when n_B = n_A).
//  - Vote: the weight drops by one (a majority vote, Boyer-Moore); at a tie the newer class wins.
//    The class seen in more than half of a voxel's frames wins, in any order, as long as the count
//    stays below max_weight (the count saturates there), and the result needs no random numbers.
// The random numbers are a hash of the voxel's grid position and the scene's integration number, so
// a run gives the same map every time and with any number of threads, and the CPU and CUDA layers
// draw the same numbers.

#include <cstdint>

#include "voxfuse/core/Math.h"
#include "voxfuse/objects/ClassLabel.h"

namespace voxfuse {

enum class LabelUpdate { Probabilistic, Vote };

// A uniform number in [0, 1) from a voxel position and a per-frame seed (a 32-bit integer hash with
// good avalanche, applied to each coordinate in turn).
VF_HOST_DEVICE inline float labelRandom(Vec3i voxel, std::uint32_t seed) {
    auto mix = [](std::uint32_t h) {
        h ^= h >> 16;
        h *= 0x7feb352du;
        h ^= h >> 15;
        h *= 0x846ca68bu;
        h ^= h >> 16;
        return h;
    };
    std::uint32_t h = mix(seed ^ 0x9e3779b9u);
    h = mix(h ^ std::uint32_t(voxel.x));
    h = mix(h ^ std::uint32_t(voxel.y));
    h = mix(h ^ std::uint32_t(voxel.z));
    return float(h >> 8) * (1.f / 16777216.f);
}

// Updates (label, weight) with one observation of class `observed` (not kNoLabel). `random` is
// uniform in [0, 1) and used by the probabilistic rule only.
VF_HOST_DEVICE inline void fuseLabel(ClassId& label, std::uint8_t& weight, ClassId observed, LabelUpdate rule,
                                     int max_weight, float random) {
    if (weight == 0) {
        label = observed;
        weight = 1;
        return;
    }
    if (label == observed) {
        if (weight < max_weight) ++weight;
        return;
    }
    if (rule == LabelUpdate::Probabilistic) {
        const float w_old = float(weight), w_new = 1.f;
        if (random < w_new / (w_old + w_new)) {
            label = observed;
            weight = 1;
        }
        return;
    }
    if (weight > 1) {
        --weight;
    } else {
        label = observed;
        weight = 1;
    }
}

}  // namespace voxfuse
