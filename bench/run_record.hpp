// How a benchmark program says where and when it ran, and keeps its section of bench/RESULTS.md:
// the CPU, the load average, the date, process CPU time (on a shared machine the work a run did,
// where wall-clock time also counts other jobs), medians of repeated runs, and a section between
// two markers that each run replaces. Shared by accuracy_chart.cpp and sampling_chart.cpp.
#pragma once

#include <time.h>

#include <algorithm>
#include <cstddef>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace prism::bench {

// CPU time of the whole process (every thread), in seconds.
inline double process_cpu_seconds() {
    timespec now{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
    return double(now.tv_sec) + 1e-9 * double(now.tv_nsec);
}

// Times of the runs of one measurement.
struct Times {
    std::vector<double> seconds;
    double median() const {
        std::vector<double> sorted = seconds;
        std::sort(sorted.begin(), sorted.end());
        const std::size_t n = sorted.size();
        return n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
    }
    double fastest() const { return *std::min_element(seconds.begin(), seconds.end()); }
    double slowest() const { return *std::max_element(seconds.begin(), seconds.end()); }
};

inline std::string cpu_model() {
    std::ifstream cpuinfo("/proc/cpuinfo");
    std::string line;
    while (std::getline(cpuinfo, line))
        if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
    return "unknown";
}

inline std::string load_average() {
    std::ifstream file("/proc/loadavg");
    std::string one, five, fifteen;
    file >> one >> five >> fifteen;
    return one + ", " + five + ", " + fifteen;
}

inline std::string utc_now() {
    const std::time_t now = std::time(nullptr);
    char text[64];
    std::strftime(text, sizeof text, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
    return text;
}

// Replaces what lies between begin_marker and end_marker in the markdown file at path, or
// appends `heading` and the marked section when the file has neither marker. Written to a
// temporary file and renamed, so an interrupted run leaves the old file.
inline void update_marked_section(const std::filesystem::path& path, const std::string& begin_marker,
                                  const std::string& end_marker, const std::string& heading,
                                  const std::string& section) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("could not read " + path.string());
    std::stringstream buffer;
    buffer << in.rdbuf();
    std::string text = buffer.str();
    const std::size_t begin = text.find(begin_marker);
    const std::size_t end = text.find(end_marker);
    const std::string marked = begin_marker + "\n\n" + section + "\n" + end_marker;
    if (begin == std::string::npos || end == std::string::npos || end < begin) {
        if (begin != std::string::npos || end != std::string::npos)
            throw std::runtime_error(path.string() + ": only one of the markers " + begin_marker + " and " + end_marker +
                                     " is there");
        if (!text.empty() && text.back() != '\n') text += '\n';
        text += "\n" + heading + "\n\n" + marked + "\n";
    } else {
        text.replace(begin, end + end_marker.size() - begin, marked);
    }
    const std::filesystem::path temporary = path.string() + ".tmp";
    {
        std::ofstream out(temporary);
        out << text;
        if (!out) throw std::runtime_error("could not write " + temporary.string());
    }
    std::filesystem::rename(temporary, path);
}

// Every file a chart needs, checked before anything is rendered: one error naming each missing
// one. `files` holds (name as the chart shows it, path under `shared`) pairs.
template <class Files>
void require_files(const std::filesystem::path& shared, const Files& files) {
    std::string missing;
    for (const auto& [name, file] : files)
        if (!std::filesystem::exists(shared / file)) missing += "\n  " + name + ": " + (shared / file).string();
    if (!missing.empty())
        throw std::runtime_error("scene file(s) not found (set --shared to the folder holding ceng795/):" + missing);
}

// A benchmark program's main: its run, and any error as one line naming the program, exit 1.
inline int run_reporting_errors(const char* program, int (*run)(int, char**), int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const std::exception& error) {
        std::cerr << program << ": " << error.what() << "\n";
        return 1;
    }
}

}  // namespace prism::bench
