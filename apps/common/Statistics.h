#pragma once
// Small numeric helpers for reports.

#include <algorithm>
#include <vector>

namespace voxfuse::app {

inline double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    const std::size_t mid = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + mid, v.end());
    const double upper = v[mid];
    if (v.size() % 2) return upper;
    return 0.5 * (upper + *std::max_element(v.begin(), v.begin() + mid));
}

}  // namespace voxfuse::app
