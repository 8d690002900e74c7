#pragma once
// A team: threads that work on one item together, share memory and wait for each other. On the GPU it
// is a CUDA thread block; on the CPU one thread, for which waiting is nothing (a test runs teams of
// several OpenMP threads on the CPU, which wait at an OpenMP barrier). A loop body written for
// a team (TDevice::parallelForTeams) splits its item's work as `for (k = team.rank; k < n; k += team.size)`
// and calls team.sync() between phases, so that one body serves both devices.

#include "voxfuse/core/Platform.h"

namespace voxfuse {

struct Team {
    int rank;  // this thread's place in the team, 0 .. size - 1
    int size;

    // Every thread of the team reaches this point before any goes on, and sees what the others wrote to
    // the team's shared memory. Every thread of the team must call it, the same number of times.
    VF_HOST_DEVICE void sync() const {
#if defined(__CUDA_ARCH__)
        __syncthreads();
#elif defined(_OPENMP)
        if (size > 1) {
            _Pragma("omp barrier")
        }
#endif
    }
};

}  // namespace voxfuse
