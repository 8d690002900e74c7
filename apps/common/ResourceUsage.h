#pragma once
// Resident memory of this process: its peak over the whole run, and (Linux) the peak over one stage,
// measured by resetting the kernel's high-water mark before it.

#include <sys/resource.h>

#include <fstream>
#include <string>

namespace voxfuse::app {

inline double peakRssMb() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_maxrss) / 1024.0;  // Linux reports kilobytes
}

// A field of /proc/self/status in MB ("VmRSS", "VmHWM"), or a negative number where there is none.
inline double procStatusMb(const std::string& field) {
    std::ifstream in("/proc/self/status");
    std::string key;
    double kb = 0.0;
    while (in >> key) {
        if (key == field + ":" && (in >> kb)) return kb / 1024.0;
        in.ignore(1 << 12, '\n');
    }
    return -1.0;
}

// Measures the extra resident memory a stage needs at its peak: construct before the stage, read
// extraMb() after it. Writing 5 to /proc/self/clear_refs resets VmHWM to the current RSS (Linux 4.0
// and later); where that fails, valid() is false and extraMb() means nothing.
class StagePeakMemory {
public:
    StagePeakMemory() {
        std::ofstream clear("/proc/self/clear_refs");
        clear << "5";
        clear.flush();
        valid_ = bool(clear);
        baseline_mb_ = procStatusMb("VmRSS");
        valid_ = valid_ && baseline_mb_ >= 0.0 && procStatusMb("VmHWM") >= 0.0;
    }
    bool valid() const { return valid_; }
    double extraMb() const { return valid_ ? procStatusMb("VmHWM") - baseline_mb_ : -1.0; }

private:
    bool valid_ = false;
    double baseline_mb_ = 0.0;
};

}  // namespace voxfuse::app
