#pragma once
// The element of a list sorted by time that is nearest to a time t, if within max_dt of it (inclusive).
// Of two equally near, the earlier wins: it was taken at or before t. Shared by trajectory evaluation
// and the label stream.

#include <algorithm>
#include <cmath>
#include <vector>

namespace voxfuse {

// `time_of(element)` gives an element's time; `sorted` is ascending in it. nullptr when none fits.
template <class T, class TimeOf>
const T* nearestInTime(const std::vector<T>& sorted, double t, double max_dt, TimeOf time_of) {
    const auto after =
        std::lower_bound(sorted.begin(), sorted.end(), t, [&](const T& e, double time) { return time_of(e) < time; });
    const T* best = after != sorted.end() ? &*after : nullptr;
    if (after != sorted.begin() && (!best || t - time_of(*std::prev(after)) <= time_of(*best) - t))
        best = &*std::prev(after);
    return best && std::fabs(time_of(*best) - t) <= max_dt ? best : nullptr;
}

}  // namespace voxfuse
