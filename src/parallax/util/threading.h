#pragma once

#include <cstddef>
#include <functional>

namespace parallax {

// Number of worker threads to use: `requested` if positive, else the number of cores the
// calling thread may run on (its affinity mask: all of the machine's unless a launcher or
// a cpuset bound the process to fewer).
int EffectiveNumThreads(int requested);

// Runs body(i) for i in [begin, end) on up to num_threads threads with dynamic scheduling
// (an atomic counter), so uneven work items balance. The first exception thrown by a body is
// rethrown on the calling thread after all workers stop.
void ParallelFor(size_t begin, size_t end, int num_threads,
                 const std::function<void(size_t)>& body);

}  // namespace parallax
