// One pass over [0, count) split into runs for TBB's threads, or left on the calling thread
// where the array is too short for a task to pay.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>

namespace prism {

// Calls run(first, end) on runs covering [0, count): one run on the calling thread below two
// grains (a task costs more than it saves there); above, TBB's runs (it splits a run while it
// holds more than `grain`) on every thread. The runs are disjoint, so a run may write its own
// elements without a lock.
template <class Run>
void for_each_run(std::size_t count, std::size_t grain, const Run& run) {
    if (count < 2 * grain) {
        run(std::size_t(0), count);
        return;
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, grain),
                      [&](const tbb::blocked_range<std::size_t>& range) { run(range.begin(), range.end()); });
}

}  // namespace prism
