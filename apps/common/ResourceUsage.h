#pragma once
// Peak resident memory of this process.

#include <sys/resource.h>

namespace voxfuse::app {

inline double peakRssMb() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_maxrss) / 1024.0;  // Linux reports kilobytes
}

}  // namespace voxfuse::app
