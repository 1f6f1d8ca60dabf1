// How cost grows (issue 11, item 8): the course's dragon_lowres subdivided 0 to 4 times (11,971 to
// 3,064,576 triangles, at its original size), rendered by the renderer with prism's own BVH and,
// when built with Embree, with Embree as the accelerator, at 1 and 2 threads. Per level and
// accelerator: build time, accelerator memory in bytes per triangle, render time (median of
// --runs), and the answer checks: every image bit-identical at 1 and 2 threads, and Embree's
// image within rounding ties of prism's (at most 0.5% of pixels off by more than 1/255, the
// limit of tests/test_embree.cpp). Stops with an error when a check fails.
//
//   prism_scaling_bench [--levels N] [--runs N] [--scale S]
//
// No Google Benchmark: each figure is one build or the median of a few whole renders, timed by
// the wall clock and by the process's CPU time (both threads summed).
#include <prism/image/compare.hpp>
#include <prism/image/image_io.hpp>
#include <prism/io/load.hpp>
#include <prism/render/render_scene.hpp>
#include <prism/render/renderer.hpp>
#include <prism/scene/stress.hpp>

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif

namespace {

const std::filesystem::path dragon_file =
    std::filesystem::path(PRISM_SHARED_DIR) / "ceng795/hw1/2020_ozgurcanc/assets/scenes/dragon_lowres.xml";

double process_cpu_seconds() {
    timespec now{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
    return double(now.tv_sec) + 1e-9 * double(now.tv_nsec);
}
double wall_seconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Timing {
    double wall = 0, cpu = 0;
};
double median(std::vector<double> values) {
    std::sort(values.begin(), values.end());
    return values[values.size() / 2];
}

struct Measured {
    Timing build;
    double bytes_per_triangle = 0;
    Timing render;  // medians
    std::vector<std::uint8_t> image;
};

template <class Acceleration>
std::size_t accelerator_bytes(const auto& geometry) {
#ifdef PRISM_WITH_EMBREE
    if constexpr (std::is_same_v<Acceleration, prism::Embree>) return std::size_t(geometry.embree_bytes());
    else
#endif
        return geometry.accelerator_bytes();
}

template <class Acceleration>
Measured measure(const prism::scene::Scene& scene, int threads, int runs, double scale) {
    using C = prism::Config<float, Acceleration>;
    const tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    Measured result;
    const double wall0 = wall_seconds(), cpu0 = process_cpu_seconds();
    const prism::Renderer<C> renderer(scene);
    result.build = {wall_seconds() - wall0, process_cpu_seconds() - cpu0};
    result.bytes_per_triangle =
        double(accelerator_bytes<Acceleration>(renderer.geometry())) / double(renderer.geometry().triangle_count());
    const prism::scene::Camera& camera = scene.cameras.at(0);
    const int width = prism::scaled_size(camera.width, scale), height = prism::scaled_size(camera.height, scale);
    std::vector<double> walls, cpus;
    for (int run = 0; run < runs; ++run) {
        const double w = wall_seconds(), c = process_cpu_seconds();
        const prism::Image image = renderer.render(camera, width, height);
        walls.push_back(wall_seconds() - w);
        cpus.push_back(process_cpu_seconds() - c);
        std::vector<std::uint8_t> bytes = prism::to_8bit(image);
        if (run > 0 && bytes != result.image) throw std::runtime_error("a render differs from the first one");
        result.image = std::move(bytes);
    }
    result.render = {median(walls), median(cpus)};
    return result;
}

void print(const char* accelerator, int level, std::size_t triangles, int threads, const Measured& m) {
    std::printf("%d\t%zu\t%s\t%d\t%.1f\t%.1f\t%.1f\t%.1f\t%.1f\n", level, triangles, accelerator, threads,
                1e3 * m.build.wall, 1e3 * m.build.cpu, m.bytes_per_triangle, 1e3 * m.render.wall, 1e3 * m.render.cpu);
    std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
    int levels = 4, runs = 3;
    double scale = 0.5;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string option = argv[i];
        if (option == "--levels") levels = std::stoi(argv[i + 1]);
        else if (option == "--runs") runs = std::stoi(argv[i + 1]);
        else if (option == "--scale") scale = std::stod(argv[i + 1]);
        else {
            std::cerr << "usage: prism_scaling_bench [--levels N] [--runs N] [--scale S]\n";
            return 2;
        }
    }
    try {
        if (!std::filesystem::exists(dragon_file)) throw std::runtime_error(dragon_file.string() + " not found");
        std::printf("level\ttriangles\taccelerator\tthreads\tbuild_wall_ms\tbuild_cpu_ms\tbytes_per_triangle\t"
                    "render_wall_ms\trender_cpu_ms\n");
        for (int level = 0; level <= levels; ++level) {
            prism::scene::Scene scene = prism::io::load_scene(dragon_file);
            if (level > 0) prism::scene::subdivide_largest_mesh(scene, level);
            std::size_t triangles = 0;
            for (const auto& mesh : scene.meshes) triangles += mesh.triangles.size();
            std::vector<std::uint8_t> reference;
            for (int threads : {1, 2}) {
                // The structure the shipped float renderer builds (the wide BVH of this machine's width).
                const Measured own =
                    measure<prism::PrecisionPolicy<prism::Precision::single>::Acceleration>(scene, threads, runs, scale);
                print("prism", level, triangles, threads, own);
                if (threads == 1) reference = own.image;
                else if (own.image != reference) throw std::runtime_error("prism: 2 threads rendered another image");
#ifdef PRISM_WITH_EMBREE
                const Measured embree = measure<prism::Embree>(scene, threads, runs, scale);
                print("embree", level, triangles, threads, embree);
                const double off = prism::share_off_by_more_than(embree.image, reference, 1);
                if (off > 0.005)
                    throw std::runtime_error("embree: " + std::to_string(100 * off) + "% of pixels off prism's image");
#endif
            }
        }
    } catch (const std::exception& error) {
        std::cerr << "prism_scaling_bench: " << error.what() << '\n';
        return 1;
    }
    return 0;
}
