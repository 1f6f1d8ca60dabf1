// What "model no more than a scene needs" saves, and what the course's sampled lights cost
// (Google Benchmark):
//   - the same point-lit course scene rendered by the fitted renderer (Lights<PointLight>, no
//     per-ray features) and by the complete one (every light type, textures, motion blur),
//     whose images must be identical (checked before timing; a mismatch stops the run);
//   - one area-light sample (point on the parallelogram, direction, estimate), float and double.
// Rendering runs on one thread so the ratio compares the code, not the scheduler. See
// bench/RESULTS.md for figures and the command.
#include <prism/io/load.hpp>
#include <prism/light/area_light.hpp>
#include <prism/render/render_scene.hpp>
#include <prism/render/renderer.hpp>

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <type_traits>

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif

namespace {

namespace scene = prism::scene;

// A point-lit course scene with several objects and mirrors: the cost of carrying unused light
// types and features shows on every shading point and every bounce.
const std::filesystem::path workload = std::filesystem::path(PRISM_SHARED_DIR) / "ceng795/hw2/2025F_Arda1333/inputs/mirror_room.json";

const scene::Scene& course_scene() {
    static const scene::Scene loaded = [] {
        if (!std::filesystem::exists(workload)) {
            std::fprintf(stderr, "render_bench: %s not found (the shared course data)\n", workload.c_str());
            std::exit(1);
        }
        scene::Scene s = prism::io::load_scene(workload);
        for (auto& camera : s.cameras) {  // a quarter of the pixels keeps a repetition short
            camera.width /= 2;
            camera.height /= 2;
        }
        return s;
    }();
    return loaded;
}

// The two ray tracers `prism` ships for each precision (render/render_scene.hpp, ShippedConfigs):
// the same acceleration structure and sampler policy, the fitted light set and features or all.
template <class Real>
using Acceleration = typename prism::PrecisionPolicy<std::is_same_v<Real, float> ? prism::Precision::single
                                                                                 : prism::Precision::double_all>::Acceleration;
template <class Real>
using Fitted = prism::Config<Real, Acceleration<Real>, prism::PointLightSet, prism::no_features, prism::Whitted,
                             prism::ChosenPattern>;
template <class Real>
using Complete = prism::Config<Real, Acceleration<Real>, prism::AllLightSet, prism::all_features, prism::Whitted,
                               prism::ChosenPattern>;

// Both renderers must produce the same image, bit for bit: the complete one only carries code
// the scene does not use.
template <class Real>
void check_same_image() {
    static bool checked = false;
    if (checked) return;
    const scene::Scene& s = course_scene();
    const prism::Renderer<Fitted<Real>> fitted(s);
    const prism::Renderer<Complete<Real>> complete(s);
    if (fitted.render(s.cameras[0]).pixels != complete.render(s.cameras[0]).pixels) {
        std::fprintf(stderr, "render_bench: the fitted and complete renderers disagree on %s\n", workload.c_str());
        std::exit(1);
    }
    checked = true;
}

template <class C>
void BM_Render(benchmark::State& state) {
    tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    check_same_image<typename C::Real>();
    const scene::Scene& s = course_scene();
    const prism::Renderer<C> renderer(s);
    for (auto _ : state) {
        prism::Image image = renderer.render(s.cameras[0]);
        benchmark::DoNotOptimize(image.pixels.data());
    }
    state.counters["pixels/s"] = benchmark::Counter(double(s.cameras[0].width) * s.cameras[0].height,
                                                    benchmark::Counter::kIsIterationInvariantRate);
}

template <class Real>
void BM_AreaLightSample(benchmark::State& state) {
    scene::Scene s;
    s.area_lights.push_back({"panel", {-1, 3, -1}, {2, 0, 0}, {0, 0, 2}, {10, 10, 10}});
    const prism::AreaLight<Real> light = prism::AreaLight<Real>::from_scene(s)[0];
    prism::Random random(1);
    const prism::ShadingFrame<Real> at{prism::Vec3<Real>(Real(0.1), 0, Real(-0.2)), prism::Vec3<Real>(0, 1, 0)};
    double sum = 0;
    for (auto _ : state) {
        const prism::LightSample<Real> sample = light.sample(at, random.uniform2<Real>());
        sum += double(sample.radiance.r);
    }
    // The estimates average to 10 * integral cos_light / d^2 dA over the panel, 3.9805 (midpoint
    // quadrature on a 2000 x 2000 grid; measured 3.9805 in float and double): a check that the
    // work was done and done right, within 1% (over 100,000 samples the mean's standard error is
    // about 0.002).
    const double mean = sum / double(state.iterations());
    if (state.iterations() > 100000 && !(std::abs(mean - 3.9805) < 0.04)) state.SkipWithError("area light estimate is off");
    state.counters["mean"] = mean;
}

}  // namespace

BENCHMARK(BM_Render<Fitted<float>>)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_Render<Complete<float>>)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_Render<Fitted<double>>)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_Render<Complete<double>>)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_AreaLightSample<float>);
BENCHMARK(BM_AreaLightSample<double>);

BENCHMARK_MAIN();
