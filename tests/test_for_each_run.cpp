// for_each_run (parallel/for_each_run.hpp): its runs cover [0, count) once each, on one thread
// below two grains and in TBB's runs above.
#include <prism/parallel/for_each_run.hpp>

#include <doctest/doctest.h>

#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

TEST_CASE("for_each_run covers every index exactly once") {
    for (const std::size_t count : {std::size_t(0), std::size_t(1), std::size_t(63), std::size_t(64), std::size_t(1000), std::size_t(100003)}) {
        constexpr std::size_t grain = 32;
        std::vector<std::atomic<int>> visits(count);
        std::atomic<int> runs{0};
        std::atomic<bool> other_thread{false};
        const std::thread::id caller = std::this_thread::get_id();
        prism::for_each_run(count, grain, [&](std::size_t first, std::size_t end) {
            ++runs;
            if (std::this_thread::get_id() != caller) other_thread = true;
            for (std::size_t i = first; i < end; ++i) ++visits[i];
        });
        CAPTURE(count);
        for (std::size_t i = 0; i < count; ++i) REQUIRE(visits[i].load() == 1);
        if (count < 2 * grain) {  // one run, on the calling thread
            CHECK(runs.load() == 1);
            CHECK_FALSE(other_thread.load());
        }
    }
}
