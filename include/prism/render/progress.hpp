// A progress bar for long renders: worker threads report finished pixels, one line on stderr
// shows percent, elapsed time and the estimated time left. It draws only when stderr is a
// terminal, so logs, pipes and CI output never receive carriage returns or escape codes.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>
#include <utility>

#include <unistd.h>

namespace prism {

class ProgressBar {
public:
    using Clock = std::chrono::steady_clock;

    // `total` units of work (pixels, tiles); `enabled` = false silences it (e.g. --quiet).
    explicit ProgressBar(std::size_t total, bool enabled = true, std::string label = {})
        : total_(total),
          enabled_(enabled && total > 0 && ::isatty(::fileno(stderr)) == 1),
          label_(std::move(label)),
          start_(Clock::now()),
          next_draw_(ticks(start_ + redraw_interval)) {}

    ProgressBar(const ProgressBar&) = delete;
    ProgressBar& operator=(const ProgressBar&) = delete;
    ~ProgressBar() { finish(); }

    // Called from any thread. Cheap when no redraw is due: one atomic add and one atomic load.
    void advance(std::size_t units) {
        const std::size_t done = done_.fetch_add(units, std::memory_order_relaxed) + units;
        if (!enabled_) return;
        const Clock::time_point now = Clock::now();
        std::int64_t due = next_draw_.load(std::memory_order_relaxed);
        if (ticks(now) < due) return;
        // One thread wins the right to draw this frame; the others go back to work at once.
        if (!next_draw_.compare_exchange_strong(due, ticks(now + redraw_interval), std::memory_order_relaxed)) return;
        const std::unique_lock lock(mutex_, std::try_to_lock);
        if (!lock.owns_lock() || finished_) return;
        draw(done, now);
        drawn_ = true;
    }

    // Clears the bar's line, so that what the program prints next starts on a clean line.
    // Idempotent; also run by the destructor, so an exception mid-render leaves no stale bar.
    void finish() noexcept {
        const std::lock_guard lock(mutex_);
        if (finished_) return;
        finished_ = true;
        if (drawn_) std::fputs("\r\x1b[K", stderr);
    }

    std::size_t done() const { return done_.load(std::memory_order_relaxed); }

private:
    static constexpr std::chrono::milliseconds redraw_interval{100};

    static std::int64_t ticks(Clock::time_point time) {
        return std::chrono::duration_cast<std::chrono::nanoseconds>(time.time_since_epoch()).count();
    }

    static std::string clock_text(double seconds) {
        const long total = long(seconds + 0.5);
        char text[32];
        if (total >= 3600)
            std::snprintf(text, sizeof text, "%ld:%02ld:%02ld", total / 3600, total / 60 % 60, total % 60);
        else
            std::snprintf(text, sizeof text, "%ld:%02ld", total / 60, total % 60);
        return text;
    }

    void draw(std::size_t done, Clock::time_point now) const {
        constexpr int bar_width = 30;
        const double fraction = done >= total_ ? 1.0 : double(done) / double(total_);
        const int filled = int(fraction * bar_width);
        std::string bar(std::size_t(bar_width), ' ');
        for (int i = 0; i < filled; ++i) bar[std::size_t(i)] = '=';
        if (filled < bar_width) bar[std::size_t(filled)] = '>';

        const double elapsed = std::chrono::duration<double>(now - start_).count();
        const std::string eta = fraction > 0.0 ? clock_text(elapsed * (1.0 - fraction) / fraction) : "?";
        std::string line = "\r";
        if (!label_.empty()) line += label_.substr(0, 32) + ' ';
        char numbers[96];
        std::snprintf(numbers, sizeof numbers, "[%s] %3d%%  %s elapsed, ETA %s", bar.c_str(), int(fraction * 100.0),
                      clock_text(elapsed).c_str(), eta.c_str());
        line += numbers;
        line += "\x1b[K";  // erase what a longer previous line left behind
        // One write per frame, so the line never interleaves with itself.
        std::fwrite(line.data(), 1, line.size(), stderr);
        std::fflush(stderr);
    }

    const std::size_t total_;
    const bool enabled_;
    const std::string label_;
    const Clock::time_point start_;
    std::atomic<std::size_t> done_{0};
    std::atomic<std::int64_t> next_draw_;
    std::mutex mutex_;
    bool finished_ = false;  // guarded by mutex_
    bool drawn_ = false;     // guarded by mutex_
};

}  // namespace prism
