// Speed against accuracy for sampling (issue 13, part 5): the path tracer's estimators — every
// combination of the course's RendererParams (NextEventEstimation, ImportanceSampling,
// RussianRoulette) and prism's MultipleImportanceSampling — on Cornell boxes lit by an object
// light, each rendered at a rising number of samples per pixel. Every image's error is measured
// against a long render of the same scene, and plotted against the render's CPU time: the lower
// a variant's curve, the less time it needs for a given error.
//
// All the estimators are unbiased for the same image (the path tracer bounds every path by
// MaxRecursionDepth; tests/test_path_tracer.cpp checks that they agree), so the error is noise,
// and error^2 x time tends to a constant for each: Monte Carlo efficiency is 1 / (error^2 time)
// (Veach's thesis, sec. 2.4; pbrt-v4 sec. 2.1.6), which the table gives relative to NEE with
// importance sampling, the course's usual choice. "At equal time, MIS's error is x of NEE's" is
// the square root of the inverse efficiency ratio.
//
// Answers are checked before anything is written: every render of a variant gives the same image
// bit for bit (so the timing measures one computation) and every pixel is finite; every variant's
// error falls from the lowest sample count to the highest (one converging to another image would
// level off); and the reference's own error, estimated from two independent halves, is at most a
// third of the smallest error the chart shows (so the chart measures the variants, not the
// reference).
#include <prism/io/load.hpp>
#include <prism/render/path_tracer.hpp>
#include <prism/render/render_scene.hpp>
#include <prism/render/renderer.hpp>

#include "run_record.hpp"
#include "svg_plot.hpp"

#include <tbb/info.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <numeric>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif
#ifndef PRISM_SOURCE_DIR
#define PRISM_SOURCE_DIR "."
#endif

namespace {

namespace fs = std::filesystem;
using namespace prism::bench;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

[[noreturn]] void fail(const std::string& message) { throw std::runtime_error(message); }

// ---------------------------------------------------------------------------------------------
// What is rendered

// The renderer every variant uses: the scene's default float precision and accelerator, object
// lights only (the chart's scenes have nothing else; a scene needing more is refused by name).
using ChartConfig = prism::Config<float, prism::PrecisionPolicy<prism::Precision::single>::Acceleration,
                                  prism::Lights<prism::LightMesh, prism::LightSphere>, prism::no_features,
                                  prism::PathTracer, prism::ChosenPattern>;
using ChartRenderer = prism::Renderer<ChartConfig>;

struct Variant {
    std::string name;
    std::string marker;
    std::string colour;
    prism::scene::RendererParams params;
};

prism::scene::RendererParams params(bool next_event, bool importance, bool roulette, bool mis = false) {
    prism::scene::RendererParams p;
    p.path_tracing = true;
    p.next_event_estimation = next_event || mis;
    p.importance_sampling = importance;
    p.russian_roulette = roulette;
    p.multiple_importance = mis;
    return p;
}

// The course's eight combinations, then MIS. The baseline of the efficiency column is NEE + IS.
const std::vector<Variant>& variants() {
    static const std::vector<Variant> list{
        {"uniform hemisphere (no parameters)", "cross", "#999999", params(false, false, false)},
        {"RussianRoulette", "plus", "#BBBBBB", params(false, false, true)},
        {"ImportanceSampling", "triangle_down", "#E69F00", params(false, true, false)},
        {"ImportanceSampling RussianRoulette", "triangle_up", "#F0E442", params(false, true, true)},
        {"NextEventEstimation", "diamond", "#56B4E9", params(true, false, false)},
        {"NextEventEstimation RussianRoulette", "star", "#0072B2", params(true, false, true)},
        {"NextEventEstimation ImportanceSampling", "square", "#009E73", params(true, true, false)},
        {"NextEventEstimation ImportanceSampling RussianRoulette", "circle", "#117733", params(true, true, true)},
        {"MIS (NEE + IS, power heuristic)", "square", "#D55E00", params(true, true, false, true)},
        {"MIS RussianRoulette", "circle", "#CC79A7", params(true, true, true, true)},
    };
    return list;
}
constexpr std::size_t baseline_variant = 6;   // NextEventEstimation ImportanceSampling
constexpr std::size_t reference_variant = 8;  // MIS: the lowest-variance estimator for the reference

struct ChartScene {
    std::string name;
    std::string file;  // under the shared folder
};

const std::string hw7_inputs = "ceng795/hw7_pathtracing_objlights/2022F_Batucan2601/hw6/";

// Scenes lit by object lights alone: a point light (cornellbox_jaroslav_path_diffuse has one) can
// only be reached by next-event estimation, so the estimators without it would converge to
// another image and the chart would compare bias, not noise.
const std::vector<ChartScene>& chart_scenes() {
    static const std::vector<ChartScene> list{
        {"path_glass: glass and mirror spheres, LightMesh box",
         hw7_inputs + "pathTracing/inputs/cornellbox_jaroslav_path_glass.xml"},
        {"glossy_area_small: Phong 90 to 600, small LightMesh box",
         hw7_inputs + "directLighting/inputs/cornellbox_jaroslav_glossy_area_small.xml"},
    };
    return list;
}

struct Options {
    double scale = 0.125;
    std::vector<int> samples{1, 4, 16, 64, 256};
    int reference_samples = 8192;
    int runs = 3;
    // The samplers' renders whose errors each point's error averages (seeds 0 to N - 1): one
    // seed's error ratio on glossy_area_small at 16 samples ranged over 0.63-0.93 between seeds.
    int error_seeds = 4;
    prism::SamplerKind sampler = prism::SamplerKind::independent;  // the RendererParams chart's
    fs::path shared = PRISM_SHARED_DIR;
    fs::path project = PRISM_SOURCE_DIR;
    fs::path output_dir = "bench/chart";
    fs::path results;
    std::string command;
    std::string revision;
    // --samplers-only: the samplers' section alone (no RendererParams chart, no RESULTS.md);
    // --sampler-scene: only the sampler scenes whose names contain one of these texts. At a
    // scene's own resolution (--scale 1) the chart's defaults would take hours.
    bool samplers_only = false;
    std::vector<std::string> sampler_scene_filter;
};

// ---------------------------------------------------------------------------------------------
// Measuring

// Relative RMSE: the root mean square difference over every channel of every pixel, divided by
// the reference's mean. Dimensionless, so scenes of different brightness share one axis.
// `trimmed`: the fraction of the largest squared differences left out (fireflies: a path through
// glass to the light that one sample in millions takes, whose one pixel can outweigh the rest of
// the image; see samplers_markdown).
double relative_rmse(const prism::Image& image, const prism::Image& reference, double trimmed = 0) {
    std::vector<double> squares;
    squares.reserve(3 * image.pixels.size());
    double mean = 0;
    for (std::size_t p = 0; p < image.pixels.size(); ++p)
        for (int c = 0; c < 3; ++c) {
            const double d = double(image.pixels[p][c]) - double(reference.pixels[p][c]);
            squares.push_back(d * d);
            mean += double(reference.pixels[p][c]);
        }
    const double n = double(squares.size());
    const auto kept = squares.size() - std::size_t(trimmed * n);
    std::nth_element(squares.begin(), squares.begin() + std::ptrdiff_t(kept) - 1, squares.end());
    double square = 0;
    for (std::size_t i = 0; i < kept; ++i) square += squares[i];
    return std::sqrt(square / double(kept)) / (mean / n);
}


bool finite(const prism::Image& image) {
    for (const glm::vec3& p : image.pixels)
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
    return true;
}

struct Point {
    int samples = 0;
    Times cpu;
    double error = 0;  // relative RMSE against the reference (the samplers': root mean square over seeds)
    double lowest = 0, highest = 0;  // the samplers' points: the seeds' smallest and largest errors
};

struct SceneResult {
    std::vector<std::vector<Point>> points;  // [variant][sample count]
    int width = 0, height = 0, depth = 0;
    double reference_error = 0;  // the reference's own relative RMSE, estimated from its halves
    double reference_seconds = 0;
};

prism::scene::Camera variant_camera(const prism::scene::Camera& camera, const Variant& variant, int samples) {
    prism::scene::Camera c = camera;
    c.renderer = variant.params;
    c.num_samples = samples;
    return c;
}

SceneResult measure_scene(const ChartScene& chart_scene, const Options& options) {
    prism::scene::Scene scene = prism::io::load_scene(options.shared / chart_scene.file);
    if (scene.cameras.empty()) fail(chart_scene.name + ": the scene has no camera");
    // Every camera path traced, so that the scene's needs are the chart renderer's.
    for (prism::scene::Camera& camera : scene.cameras) camera.renderer = variants()[reference_variant].params;
    const std::string needs = prism::scene::measure_needs(scene).beyond(ChartConfig::meets);
    if (!needs.empty()) fail(chart_scene.name + ": the scene needs " + needs + ", beyond the chart's renderer");
    const prism::scene::Camera camera = scene.cameras.front();

    SceneResult result;
    result.width = prism::scaled_size(camera.width, options.scale);
    result.height = prism::scaled_size(camera.height, options.scale);
    result.depth = scene.max_recursion_depth;
    std::cerr << chart_scene.name << ": " << result.width << "x" << result.height << ", MaxRecursionDepth "
              << result.depth << "\n";

    // The reference: MIS at reference_samples, as two independent halves (seeds 1 and 2; the
    // variants use seed 0), whose difference estimates the reference's own error. Its sampler is
    // named (sobol: the least error a sample), so that a change of the default does not change it.
    const auto reference_start = Clock::now();
    const prism::scene::Camera half =
        variant_camera(camera, variants()[reference_variant], std::max(1, options.reference_samples / 2));
    const ChartRenderer first(scene, prism::RendererSettings{prism::BackfaceCulling::triangles,
                                                              prism::RayOffset::scene_epsilon, 1,
                                                              prism::SamplerKind::sobol});
    const ChartRenderer second(scene, prism::RendererSettings{prism::BackfaceCulling::triangles,
                                                               prism::RayOffset::scene_epsilon, 2,
                                                               prism::SamplerKind::sobol});
    const prism::Image a = first.render(half, result.width, result.height);
    const prism::Image b = second.render(half, result.width, result.height);
    if (!finite(a) || !finite(b)) fail(chart_scene.name + ": the reference has a pixel that is not finite");
    prism::Image reference(result.width, result.height);
    for (std::size_t p = 0; p < reference.pixels.size(); ++p) reference.pixels[p] = 0.5f * (a.pixels[p] + b.pixels[p]);
    // a - b has twice a half's variance; the mean of the halves has half of it: a quarter.
    result.reference_error = 0.5 * relative_rmse(a, b);
    result.reference_seconds = seconds_since(reference_start);
    std::cerr << "  reference: " << 2 * half.num_samples << " samples per pixel in " << std::fixed
              << std::setprecision(1) << result.reference_seconds << " s wall, own relative RMSE "
              << std::setprecision(5) << result.reference_error << std::defaultfloat << "\n";

    const ChartRenderer renderer(scene, prism::RendererSettings{prism::BackfaceCulling::triangles,
                                                                 prism::RayOffset::scene_epsilon, 0, options.sampler});
    const std::size_t count = variants().size();
    result.points.assign(count, std::vector<Point>(options.samples.size()));
    std::vector<std::size_t> order(count);
    std::iota(order.begin(), order.end(), 0);
    std::mt19937 shuffle(12345);
    for (std::size_t s = 0; s < options.samples.size(); ++s) {
        std::vector<prism::Image> images(count);
        // Round 0 is a warm-up that gives each variant's image; the timed rounds must repeat it.
        for (int round = 0; round <= options.runs; ++round) {
            std::shuffle(order.begin(), order.end(), shuffle);
            for (const std::size_t v : order) {
                const prism::scene::Camera c = variant_camera(camera, variants()[v], options.samples[s]);
                const double cpu_start = process_cpu_seconds();
                prism::Image image = renderer.render(c, result.width, result.height);
                const double cpu_seconds = process_cpu_seconds() - cpu_start;
                if (round == 0) {
                    if (!finite(image))
                        fail(chart_scene.name + ", " + variants()[v].name + ": a pixel is not finite");
                    images[v] = std::move(image);
                    continue;
                }
                if (!prism::same_bits(image, images[v]))
                    fail(chart_scene.name + ", " + variants()[v].name + ", " + std::to_string(options.samples[s]) +
                         " samples: run " + std::to_string(round) + " rendered a different image from the first");
                result.points[v][s].cpu.seconds.push_back(cpu_seconds);
            }
        }
        for (std::size_t v = 0; v < count; ++v) {
            Point& point = result.points[v][s];
            point.samples = options.samples[s];
            point.error = relative_rmse(images[v], reference);
        }
        std::cerr << "  " << options.samples[s] << " spp done\n";
    }
    for (std::size_t v = 0; v < count; ++v) {
        const std::vector<Point>& curve = result.points[v];
        std::cerr << "  " << std::left << std::setw(56) << variants()[v].name << std::right;
        for (const Point& point : curve)
            std::cerr << " " << std::setw(5) << point.samples << ": " << std::setprecision(4) << point.error << " in "
                      << std::setprecision(3) << 1e3 * point.cpu.median() << " ms;";
        std::cerr << std::defaultfloat << "\n";
    }
    return result;
}

// Efficiency 1 / (error^2 time) at the highest sample count, where the error is the variant's
// own: the reference's share of the measured error (independent noise, so variances add) taken out.
double efficiency(const Point& point, double reference_error) {
    const double own = std::max(point.error * point.error - reference_error * reference_error, 0.0);
    return own > 0 ? 1.0 / (own * point.cpu.median()) : 0.0;
}

// ---------------------------------------------------------------------------------------------
// The samplers (issue 32): each scene rendered as its first camera asks (its own integrator and
// RendererParams), through the shipped renderers (prism::render_scene, as `prism` renders it),
// with each sampler at each sample count, against a long independent render.

const std::vector<Variant>& sampler_styles() {  // in SamplerKind's order
    static const std::vector<Variant> list{
        {"independent: the pixel's PCG32 stream", "circle", "#777777", {}},
        {"stratified: every dimension, pairs multi-jittered", "square", "#0072B2", {}},
        {"sobol: Owen-scrambled Sobol', pixels in Morton order (ZSobol)", "diamond", "#D55E00", {}},
    };
    return list;
}
constexpr std::array all_samplers{prism::SamplerKind::independent, prism::SamplerKind::stratified,
                                  prism::SamplerKind::sobol};

// in_project: the file is under the project's own scenes/, not ../shared.
struct SamplerScene {
    std::string name;
    std::string file;
    bool in_project = false;
};

// Area lights and glossy reflections under the ray tracer, an object light seen by glossy
// surfaces, the path tracer through glass and between diffuse walls (the default sampler serves
// both hw7 boxes), and an environment light. ../shared has no course
// scene with an environment light (hw5's are not among its files), so that one is prism's own
// scene in the course's format (a SphericalDirectionalLight, importance-sampled).
const std::vector<SamplerScene>& sampler_scenes() {
    static const std::vector<SamplerScene> list{
        {"hw3 metal_plates_area: area lights, glossy metal, ray traced",
         "ceng795/hw3/2018S_emrebarisc/Sources/3 - Instancing, Transformation, Distribution/Scenes/metal_plates_area.xml"},
        {"glossy_area_small: LightMesh, glossy, ray traced",
         hw7_inputs + "directLighting/inputs/cornellbox_jaroslav_glossy_area_small.xml"},
        {"path_glass: path traced (NextEventEstimation)",
         hw7_inputs + "pathTracing/inputs/cornellbox_jaroslav_path_glass.xml"},
        {"path_diffuse: path traced (NextEventEstimation), diffuse",
         hw7_inputs + "pathTracing/inputs/cornellbox_jaroslav_path_diffuse.xml"},
        {"environment/latlong: SphericalDirectionalLight", "scenes/environment/latlong.xml", true},
    };
    return list;
}

fs::path sampler_scene_path(const SamplerScene& chart_scene, const Options& options) {
    return (chart_scene.in_project ? options.project : options.shared) / chart_scene.file;
}

// The share of squared differences the samplers' errors leave out (relative_rmse): one in a
// thousand. path_glass's 64 x 64 pixels at 16 samples had a relative RMSE of 0.67-3.0 with
// independent samples over seeds 0-3 and 0.55-0.69 without them; at such a spread one render's RMSE
// ranks fireflies, not samplers.
constexpr double firefly_share = 0.001;

// The seeds of the samplers' reference halves, apart from the curves' seeds.
constexpr std::uint64_t reference_seeds[2] = {1000, 1001};

struct SamplerResult {
    std::string name;  // the scene's (sampler_scenes)
    std::vector<std::vector<Point>> points;  // [sampler][sample count]; time: the camera's render, wall
    int width = 0, height = 0;
    double reference_error = 0;
};

// One render of the scene's first camera, as `prism` renders it with these options.
prism::CameraImage render_first_camera(const prism::scene::Scene& scene, const Options& options, int samples,
                                       std::uint64_t seed, prism::SamplerKind sampler) {
    prism::RenderOptions render;
    render.resolution_scale = options.scale;
    render.samples = samples;
    render.seed = seed;
    render.sampler = sampler;
    std::ostringstream log;  // the configuration's report: the same for every render
    std::vector<prism::CameraImage> images = prism::render_scene(scene, render, log);
    if (images.size() != 1) fail("expected one camera's image");
    return std::move(images.front());
}

SamplerResult measure_samplers(const SamplerScene& chart_scene, const Options& options) {
    prism::scene::Scene scene = prism::io::load_scene(sampler_scene_path(chart_scene, options));
    if (scene.cameras.empty()) fail(chart_scene.name + ": the scene has no camera");
    scene.cameras.resize(1);
    SamplerResult result;
    result.name = chart_scene.name;
    const auto reference_start = Clock::now();
    const int half = std::max(1, options.reference_samples / 2);
    // Seeds apart from the curves' (0 to error_seeds - 1).
    const prism::Image a = render_first_camera(scene, options, half, reference_seeds[0], prism::SamplerKind::independent).image;
    const prism::Image b = render_first_camera(scene, options, half, reference_seeds[1], prism::SamplerKind::independent).image;
    if (!finite(a) || !finite(b)) fail(chart_scene.name + ": the reference has a pixel that is not finite");
    prism::Image reference(a.width, a.height);
    for (std::size_t p = 0; p < reference.pixels.size(); ++p) reference.pixels[p] = 0.5f * (a.pixels[p] + b.pixels[p]);
    result.width = a.width;
    result.height = a.height;
    result.reference_error = 0.5 * relative_rmse(a, b, firefly_share);
    std::cerr << chart_scene.name << ": " << result.width << "x" << result.height << "; reference "
              << 2 * half << " samples per pixel in " << std::fixed << std::setprecision(1)
              << seconds_since(reference_start) << " s wall, own relative RMSE " << std::setprecision(5)
              << result.reference_error << std::defaultfloat << "\n";
    result.points.assign(all_samplers.size(), std::vector<Point>(options.samples.size()));
    std::vector<std::size_t> order(all_samplers.size());
    std::iota(order.begin(), order.end(), 0);
    std::mt19937 shuffle(11);
    for (std::size_t s = 0; s < options.samples.size(); ++s) {
        std::vector<prism::Image> images(all_samplers.size());
        for (int round = 0; round <= options.runs; ++round) {
            std::shuffle(order.begin(), order.end(), shuffle);
            for (const std::size_t k : order) {
                prism::CameraImage render = render_first_camera(scene, options, options.samples[s], 0, all_samplers[k]);
                const std::string name = chart_scene.name + ", " + std::string(prism::sampler_name(all_samplers[k])) +
                                         ", " + std::to_string(options.samples[s]) + " samples";
                if (round == 0) {
                    if (!finite(render.image)) fail(name + ": a pixel is not finite");
                    images[k] = std::move(render.image);
                    continue;
                }
                if (!prism::same_bits(render.image, images[k]))
                    fail(name + ": run " + std::to_string(round) + " rendered a different image from the first");
                result.points[k][s].cpu.seconds.push_back(render.seconds);
            }
        }
        for (std::size_t k = 0; k < all_samplers.size(); ++k) {
            Point& point = result.points[k][s];
            point.samples = options.samples[s];
            // The error of seed 0's render, then of the other seeds' (untimed).
            double squares = 0;
            for (int seed = 0; seed < options.error_seeds; ++seed) {
                const double error =
                    seed == 0 ? relative_rmse(images[k], reference, firefly_share)
                              : relative_rmse(render_first_camera(scene, options, options.samples[s], std::uint64_t(seed),
                                                                  all_samplers[k])
                                                  .image,
                                              reference, firefly_share);
                squares += error * error;
                point.lowest = seed == 0 ? error : std::min(point.lowest, error);
                point.highest = seed == 0 ? error : std::max(point.highest, error);
            }
            point.error = std::sqrt(squares / options.error_seeds);
        }
    }
    for (std::size_t k = 0; k < all_samplers.size(); ++k) {
        std::cerr << "  " << std::left << std::setw(12) << prism::sampler_name(all_samplers[k]) << std::right;
        for (const Point& point : result.points[k])
            std::cerr << " " << std::setw(5) << point.samples << ": " << std::setprecision(4) << point.error << " in "
                      << std::setprecision(3) << 1e3 * point.cpu.median() << " ms;";
        std::cerr << std::defaultfloat << "\n";
    }
    return result;
}

// A sampler's own error at a point (the reference's share taken out, as in efficiency), over
// independent's at the same sample count.
double error_ratio(const SamplerResult& result, std::size_t sampler, std::size_t count) {
    const auto own = [&](const Point& point) {
        return std::sqrt(std::max(point.error * point.error - result.reference_error * result.reference_error, 0.0));
    };
    const double independent = own(result.points[0][count]);
    return independent > 0 ? own(result.points[sampler][count]) / independent : 0.0;
}

std::string samplers_markdown(const std::vector<SamplerResult>& results, const Options& options,
                              const std::string& date) {
    std::ostringstream md;
    if (options.samplers_only)
        md << "Written by `" << options.command << "` on " << date << " (revision `" << options.revision
           << "`). Each scene's first camera";
    else
        md << "Written by the same command on " << date << " (revision `" << options.revision
           << "`), after the RendererParams chart. Each scene's first camera";
    md << ", rendered as `prism` renders it "
          "(`prism::render_scene`: its own integrator and RendererParams, the shipped renderers) at `--scale "
       << options.scale << "`, with `--samples N --sampler S`; the reference: independent samples at "
       << options.reference_samples
       << " samples per pixel, as two halves (seeds 1000 and 1001). Error: relative RMSE "
          "without the largest 0.1% of squared differences (fireflies: one render's full RMSE on path_glass "
          "ranged over 0.67-3.0 between seeds), the root mean square of " << options.error_seeds
       << " renders' (seeds 0 to " << options.error_seeds - 1
       << "; the ratios of one seed's errors ranged over 0.63-0.93 on glossy_area_small at 16 samples). Time: the camera's render (wall, " << tbb::info::default_concurrency()
       << " threads, loading and the BVH's build left out), median of " << options.runs
       << " runs after a warm-up, samplers interleaved. Every render repeated its first image bit for bit, every "
          "pixel is finite, every curve's error fell from the lowest sample count to the highest, and each reference's "
          "own error is at most a third of the smallest error shown.\n\n";
    md << "![samplers: error against time](chart/samplers.png)\n\n";
    md << "| scene | sampler |";
    for (const int n : options.samples) md << " " << n << " spp: error (seeds' range), ms |";
    md << " own error / independent's, 16 and 64 spp | time / independent's, highest count |\n|---|---|";
    for (std::size_t i = 0; i < options.samples.size(); ++i) md << "---|";
    md << "---|---|\n";
    const auto index_of = [&](int count) {
        const auto at = std::find(options.samples.begin(), options.samples.end(), count);
        return at == options.samples.end() ? std::optional<std::size_t>{}
                                           : std::optional<std::size_t>{std::size_t(at - options.samples.begin())};
    };
    for (std::size_t s = 0; s < results.size(); ++s) {
        const SamplerResult& result = results[s];
        for (std::size_t k = 0; k < all_samplers.size(); ++k) {
            md << "| " << (k == 0 ? result.name + " (" + std::to_string(result.width) + "x" +
                                        std::to_string(result.height) + ")"
                                  : std::string())
               << " | " << prism::sampler_name(all_samplers[k]) << " |";
            for (const Point& point : result.points[k])
                md << " " << format_number(point.error, 3) << " (" << format_number(point.lowest, 2) << "-"
                   << format_number(point.highest, 2) << "), " << std::fixed << std::setprecision(1)
                   << 1e3 * point.cpu.median() << std::defaultfloat << " |";
            std::string ratios;
            for (const int count : {16, 64})
                if (const auto i = index_of(count))
                    ratios += (ratios.empty() ? "" : ", ") + format_number(error_ratio(result, k, *i), 3);
            md << " " << (ratios.empty() ? std::string("-") : ratios) << " | "
               << format_number(result.points[k].back().cpu.median() / result.points[0].back().cpu.median(), 3)
               << " |\n";
        }
    }
    return md.str();
}

// ---------------------------------------------------------------------------------------------
// The charts (SVG): one panel per scene, time on a log x axis, relative RMSE on a log y axis, one
// line per curve (a RendererParams variant, or a sampler) through its sample counts.

struct Curve {
    const Variant* style = nullptr;  // name, marker and colour
    const std::vector<Point>* points = nullptr;
};

struct Panel {
    std::string name;
    double reference_error = 0;
    std::vector<Curve> curves;
};

struct Figure {
    std::string title;
    std::vector<std::string> subtitle;
    std::string time_axis;      // what the x axis measures
    std::string legend_title;
    std::vector<Variant> legend;
    std::string footnote;
};

// A panel's answers: every curve's error fell from its lowest sample count to its highest (one
// converging to another image would level off), and the reference's own error is at most a third
// of the smallest error shown (so the chart measures the curves, not the reference).
void check_panel(const Panel& panel) {
    double smallest = INFINITY;
    for (const Curve& curve : panel.curves) {
        const std::vector<Point>& points = *curve.points;
        smallest = std::min(smallest, points.back().error);
        if (!(points.back().error < points.front().error))
            fail(panel.name + ", " + curve.style->name + ": the error did not fall from " +
                 std::to_string(points.front().samples) + " to " + std::to_string(points.back().samples) +
                 " samples per pixel (" + format_number(points.front().error, 4) + " to " +
                 format_number(points.back().error, 4) + "): it converges to another image than the reference");
    }
    if (panel.reference_error * 3 > smallest)
        fail(panel.name + ": the reference's own error " + format_number(panel.reference_error, 3) +
             " is more than a third of the smallest error measured (" + format_number(smallest, 3) +
             "): raise --reference-samples");
}

void write_svg(const fs::path& path, const std::vector<Panel>& panels, const Figure& figure) {
    const double panel_width = 520, panel_height = 420, top = 110;
    const double width = 90 + double(panels.size()) * (panel_width + 110), height = 900;
    std::ostringstream svg;
    svg << std::fixed << std::setprecision(1);
    svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
        << "\" viewBox=\"0 0 " << width << " " << height << "\" font-family=\"DejaVu Sans, Arial, sans-serif\">\n";
    svg << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
    svg << "<text x=\"" << width / 2 << "\" y=\"32\" font-size=\"20\" text-anchor=\"middle\" font-weight=\"bold\">"
        << escape_xml(figure.title) << "</text>\n";
    for (std::size_t line = 0; line < figure.subtitle.size(); ++line)
        svg << "<text x=\"" << width / 2 << "\" y=\"" << 54 + 17 * double(line)
            << "\" font-size=\"13\" text-anchor=\"middle\">" << escape_xml(figure.subtitle[line]) << "</text>\n";
    for (std::size_t s = 0; s < panels.size(); ++s) {
        const Panel& panel = panels[s];
        const double left = 90 + double(s) * (panel_width + 110);
        std::vector<double> times, errors{panel.reference_error};
        for (const Curve& curve : panel.curves)
            for (const Point& point : *curve.points) {
                times.push_back(point.cpu.median());
                errors.push_back(point.error);
            }
        const LogAxis x_axis = log_axis(times, times.front());
        LogAxis y_axis = log_axis(errors, errors.front());
        y_axis.floor_decade += 1;  // no zero to draw here: no empty decade below the smallest error
        const auto x_of = [&](double t) {
            return left + (std::log10(t) - x_axis.floor_decade) / double(x_axis.top_decade - x_axis.floor_decade) *
                              panel_width;
        };
        const auto y_of = [&](double e) {
            const double d = std::clamp(std::log10(e), double(y_axis.floor_decade), double(y_axis.top_decade));
            return top + panel_height -
                   (d - y_axis.floor_decade) / double(y_axis.top_decade - y_axis.floor_decade) * panel_height;
        };
        svg << "<text x=\"" << left + panel_width / 2 << "\" y=\"" << top - 10
            << "\" font-size=\"13\" text-anchor=\"middle\" font-weight=\"bold\">" << escape_xml(panel.name)
            << "</text>\n";
        svg << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << panel_width << "\" height=\""
            << panel_height << "\" fill=\"none\" stroke=\"#333\"/>\n";
        for (int d = y_axis.floor_decade; d <= y_axis.top_decade; ++d) {
            const double y = y_of(std::pow(10.0, d));
            svg << "<line x1=\"" << left << "\" y1=\"" << y << "\" x2=\"" << left + panel_width << "\" y2=\"" << y
                << "\" stroke=\"#ddd\"/>\n<text x=\"" << left - 6 << "\" y=\"" << y + 4
                << "\" font-size=\"12\" text-anchor=\"end\">" << decade_label(d, false) << "</text>\n";
        }
        for (int d = x_axis.floor_decade; d <= x_axis.top_decade; ++d) {
            const double x = x_of(std::pow(10.0, d));
            svg << "<line x1=\"" << x << "\" y1=\"" << top << "\" x2=\"" << x << "\" y2=\"" << top + panel_height
                << "\" stroke=\"#ddd\"/>\n<text x=\"" << x << "\" y=\"" << top + panel_height + 18
                << "\" font-size=\"12\" text-anchor=\"middle\">" << decade_label(d, false) << "</text>\n";
        }
        // The reference's own error: a floor no curve can go below in this measurement.
        const double floor_y = y_of(panel.reference_error);
        svg << "<line x1=\"" << left << "\" y1=\"" << floor_y << "\" x2=\"" << left + panel_width << "\" y2=\""
            << floor_y << "\" stroke=\"#999\" stroke-dasharray=\"4,3\"/>\n<text x=\"" << left + panel_width - 4
            << "\" y=\"" << floor_y - 5 << "\" font-size=\"11\" text-anchor=\"end\" fill=\"#666\">the reference's own error</text>\n";
        svg << "<text x=\"" << left + panel_width / 2 << "\" y=\"" << top + panel_height + 42
            << "\" font-size=\"13\" text-anchor=\"middle\">" << escape_xml(figure.time_axis) << "</text>\n";
        svg << "<text transform=\"translate(" << left - 62 << "," << top + panel_height / 2
            << ") rotate(-90)\" font-size=\"13\" text-anchor=\"middle\">relative RMSE against the reference (log scale)</text>\n";
        for (const Curve& curve : panel.curves) {
            const Variant& style = *curve.style;
            svg << "<polyline fill=\"none\" stroke=\"" << style.colour << "\" stroke-width=\"1.5\" points=\"";
            for (const Point& point : *curve.points) svg << x_of(point.cpu.median()) << "," << y_of(point.error) << " ";
            svg << "\"/>\n";
            for (const Point& point : *curve.points)
                svg << marker_svg(style.marker, x_of(point.cpu.median()), y_of(point.error), style.colour) << "\n";
        }
    }
    const double legend_top = top + panel_height + 80;
    svg << "<text x=\"90\" y=\"" << legend_top << "\" font-size=\"14\" font-weight=\"bold\">"
        << escape_xml(figure.legend_title) << "</text>\n";
    for (std::size_t v = 0; v < figure.legend.size(); ++v) {
        const Variant& style = figure.legend[v];
        const double x = 90 + double(v / 5) * 520, y = legend_top + 24 + 24 * double(v % 5);
        svg << "<line x1=\"" << x - 4 << "\" y1=\"" << y - 4 << "\" x2=\"" << x + 24 << "\" y2=\"" << y - 4
            << "\" stroke=\"" << style.colour << "\" stroke-width=\"1.5\"/>"
            << marker_svg(style.marker, x + 10, y - 4, style.colour) << "<text x=\"" << x + 34 << "\" y=\"" << y
            << "\" font-size=\"13\">" << escape_xml(style.name) << "</text>\n";
    }
    svg << "<text x=\"90\" y=\"" << legend_top + 160 << "\" font-size=\"12\" fill=\"#444\">"
        << escape_xml(figure.footnote) << "</text>\n";
    svg << "</svg>\n";
    std::ofstream out(path);
    out << svg.str();
    if (!out) fail("could not write " + path.string());
}

// ---------------------------------------------------------------------------------------------
// The table (TSV and markdown)

void write_tsv(const fs::path& path, const std::vector<SceneResult>& results) {
    std::ofstream out(path);
    out << "scene\tvariant\twidth\theight\tsamples\trender_cpu_median_s\trender_cpu_min_s\trender_cpu_max_s\t"
           "relative_rmse\treference_relative_rmse\n";
    for (std::size_t s = 0; s < results.size(); ++s)
        for (std::size_t v = 0; v < variants().size(); ++v)
            for (const Point& point : results[s].points[v])
                out << chart_scenes()[s].name << '\t' << variants()[v].name << '\t' << results[s].width << '\t'
                    << results[s].height << '\t' << point.samples << '\t' << point.cpu.median() << '\t'
                    << point.cpu.fastest() << '\t' << point.cpu.slowest() << '\t' << point.error << '\t'
                    << results[s].reference_error << '\n';
    if (!out) fail("could not write " + path.string());
}

std::string markdown_section(const std::vector<SceneResult>& results, const Options& options, double total_seconds,
                             const std::string& start_load, const std::string& date,
                             const std::vector<std::string>& checks) {
    std::ostringstream md;
    md << "Written by this command, run from the repository's root on " << date << ":\n\n```sh\n" << options.command
       << "\n```\n\n";
    md << "- **Machine:** `nproc` = " << std::thread::hardware_concurrency() << ", CPU `" << cpu_model()
       << "` (/proc/cpuinfo), compiler " << __VERSION__ << ", Release, revision `" << options.revision << "`.\n";
    md << "- **Threads:** " << tbb::info::default_concurrency() << ". Load average before the run: " << start_load
       << "; after: " << load_average() << ". The program ran " << std::lround(total_seconds) << " s.\n";
    md << "- **Scenes** (`../shared/`, first camera, every camera switched to path tracing with the variant's "
          "parameters, resolution times `--scale "
       << options.scale << "`):";
    for (std::size_t s = 0; s < results.size(); ++s)
        md << "\n  - " << chart_scenes()[s].name << ": `" << chart_scenes()[s].file << "`, " << results[s].width << "x"
           << results[s].height << ", MaxRecursionDepth " << results[s].depth << ";";
    md << "\n- **Reference:** MIS at " << options.reference_samples
       << " samples per pixel with the sobol sampler, as two independent halves (seeds 1 and 2; the variants use "
          "seed 0); its own relative "
          "RMSE, half the RMSE between the halves:";
    for (std::size_t s = 0; s < results.size(); ++s)
        md << " " << format_number(results[s].reference_error, 3) << (s + 1 < results.size() ? "," : ".");
    md << "\n- **Error:** relative RMSE in linear radiance (root mean square difference over every channel of every "
          "pixel, divided by the reference's mean). **Efficiency:** 1 / (error² × CPU time) at the highest sample "
          "count, the reference's own error² taken out, relative to NextEventEstimation ImportanceSampling; "
          "at equal time a variant's error is 1 / sqrt(its efficiency) of that baseline's.\n";
    md << "- **Checked before writing:**";
    for (const std::string& check : checks) md << "\n  - " << check;
    md << "\n\n![sampling: error against time](chart/sampling.png)\n\n";
    md << "| scene | variant |";
    for (const int n : options.samples) md << " " << n << " spp: error, CPU ms |";
    md << " efficiency vs NEE+IS | error at equal time vs NEE+IS |\n|---|---|";
    for (std::size_t i = 0; i < options.samples.size(); ++i) md << "---|";
    md << "---|---|\n";
    for (std::size_t s = 0; s < results.size(); ++s) {
        const double base = efficiency(results[s].points[baseline_variant].back(), results[s].reference_error);
        for (std::size_t v = 0; v < variants().size(); ++v) {
            md << "| " << (v == 0 ? chart_scenes()[s].name : std::string()) << " | " << variants()[v].name << " |";
            for (const Point& point : results[s].points[v])
                md << " " << format_number(point.error, 3) << ", " << std::fixed << std::setprecision(1)
                   << 1e3 * point.cpu.median() << std::defaultfloat << " |";
            const double relative = base > 0 ? efficiency(results[s].points[v].back(), results[s].reference_error) / base : 0;
            md << " " << format_number(relative, 3) << " | "
               << (relative > 0 ? format_number(1.0 / std::sqrt(relative), 3) : std::string("-")) << " |\n";
        }
    }
    return md.str();
}

const std::string begin_marker = "<!-- sampling_chart:begin (written by tools/chart.sh sampling; edits inside are overwritten) -->";
const std::string end_marker = "<!-- sampling_chart:end -->";

// ---------------------------------------------------------------------------------------------

const char* usage =
    "usage: prism_sampling_chart [--scale S] [--samples N,N,...] [--reference-samples N] [--runs N]\n"
    "                            [--error-seeds N]\n"
    "                            [--shared DIR] [--output-dir DIR] [--results RESULTS.md] [--command TEXT]\n"
    "                            [--revision TEXT]\n"
    "                            [--sampler independent|stratified|sobol] [--project DIR]\n"
    "                            [--samplers-only] [--sampler-scene TEXT]...\n"
    "Renders the chart's Cornell boxes with every path-tracing variant at each sample count (with\n"
    "--sampler's samples), measures each image's relative RMSE against a long MIS render, and times\n"
    "the renders; then renders five scenes as prism renders them with each sampler at each count,\n"
    "against a long independent render. Writes DIR/sampling.svg, DIR/samplers.svg, DIR/sampling.tsv\n"
    "and DIR/sampling.md, and replaces the marked section of RESULTS.md when given. Defaults:\n"
    "--scale 0.125, --samples 1,4,16,64,256, --reference-samples 8192, --runs 3 (timed runs after one\n"
    "warm-up), --error-seeds 4 (the samplers' renders whose errors a point averages), --sampler independent, --shared " PRISM_SHARED_DIR ", --project " PRISM_SOURCE_DIR ".\n"
    "--samplers-only renders the sampler scenes alone and writes DIR/samplers.svg and DIR/samplers.md (not\n"
    "RESULTS.md, whose section holds both charts); --sampler-scene TEXT keeps the scenes whose names\n"
    "contain TEXT (metal_plates_area, glossy_area_small, path_glass, path_diffuse, latlong;\n"
    "repeatable).\n";

std::vector<int> parse_counts(const std::string& text) {
    std::vector<int> counts;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        std::size_t used = 0;
        const int n = std::stoi(item, &used);
        if (used != item.size() || n < 1 || n > 65536) fail("--samples: \"" + item + "\" is not a count in [1, 65536]");
        if (!counts.empty() && n <= counts.back()) fail("--samples: the counts must rise");
        counts.push_back(n);
    }
    if (counts.size() < 2) fail("--samples needs at least two counts");
    return counts;
}

Options parse(int argc, char** argv) {
    Options options;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        const auto value = [&]() -> std::string {
            if (i + 1 >= argc) fail(arg + " needs a value\n" + usage);
            return argv[++i];
        };
        if (arg == "--scale") options.scale = std::stod(value());
        else if (arg == "--samples") options.samples = parse_counts(value());
        else if (arg == "--reference-samples") options.reference_samples = std::stoi(value());
        else if (arg == "--runs") options.runs = std::stoi(value());
        else if (arg == "--error-seeds") options.error_seeds = std::stoi(value());
        else if (arg == "--shared") options.shared = value();
        else if (arg == "--project") options.project = value();
        else if (arg == "--sampler") {
            const std::string name = value();
            const std::optional<prism::SamplerKind> kind = prism::parse_sampler(name);
            if (!kind) fail("--sampler must be independent, stratified or sobol, not \"" + name + "\"");
            options.sampler = *kind;
        }
        else if (arg == "--output-dir") options.output_dir = value();
        else if (arg == "--results") options.results = value();
        else if (arg == "--command") options.command = value();
        else if (arg == "--revision") options.revision = value();
        else if (arg == "--samplers-only") options.samplers_only = true;
        else if (arg == "--sampler-scene") options.sampler_scene_filter.push_back(value());
        else if (arg == "--help" || arg == "-h") {
            std::cout << usage;
            std::exit(0);
        } else fail("unknown option " + arg + "\n" + usage);
    }
    if (!(options.scale > 0.0 && options.scale <= 1.0)) fail("--scale must be in (0, 1]");
    if (options.runs < 1) fail("--runs must be at least 1");
    if (options.error_seeds < 1 || options.error_seeds > 64) fail("--error-seeds must be in [1, 64]");
    if (options.reference_samples < 4 * options.samples.back() || options.reference_samples > 65536)
        fail("--reference-samples must be in [4 x the highest --samples, 65536]");
    if (options.samplers_only && !options.results.empty())
        fail("--results replaces the section of both charts: not with --samplers-only");
    for (const std::string& text : options.sampler_scene_filter) {
        const auto& scenes = sampler_scenes();
        if (std::none_of(scenes.begin(), scenes.end(),
                         [&](const SamplerScene& scene) { return scene.name.find(text) != std::string::npos; }))
            fail("--sampler-scene: no sampler scene's name contains \"" + text + "\"");
    }
    if (options.command.empty()) options.command = "prism_sampling_chart";
    if (options.revision.empty()) options.revision = "unknown";
    return options;
}

int run(int argc, char** argv) {
    const auto start = Clock::now();
    const std::string start_load = load_average();
    const std::string date = utc_now();
    const Options options = parse(argc, argv);
    std::vector<std::pair<std::string, std::string>> files;
    for (const ChartScene& chart_scene : chart_scenes()) files.emplace_back(chart_scene.name, chart_scene.file);
    require_files(options.shared, files);
    fs::create_directories(options.output_dir);

    std::vector<SamplerScene> chosen_scenes;
    for (const SamplerScene& chart_scene : sampler_scenes()) {
        const auto& filter = options.sampler_scene_filter;
        if (filter.empty() || std::any_of(filter.begin(), filter.end(), [&](const std::string& text) {
                return chart_scene.name.find(text) != std::string::npos;
            }))
            chosen_scenes.push_back(chart_scene);
    }
    for (const SamplerScene& chart_scene : chosen_scenes)
        if (!fs::exists(sampler_scene_path(chart_scene, options)))
            fail(chart_scene.name + ": " + sampler_scene_path(chart_scene, options).string() + " not found");
    std::vector<SceneResult> results;
    if (!options.samplers_only)
        for (const ChartScene& chart_scene : chart_scenes()) results.push_back(measure_scene(chart_scene, options));
    std::vector<SamplerResult> sampler_results;
    for (const SamplerScene& chart_scene : chosen_scenes) sampler_results.push_back(measure_samplers(chart_scene, options));

    std::vector<Panel> panels;
    for (std::size_t s = 0; s < results.size(); ++s) {
        Panel panel{chart_scenes()[s].name, results[s].reference_error, {}};
        for (std::size_t v = 0; v < variants().size(); ++v) panel.curves.push_back({&variants()[v], &results[s].points[v]});
        panels.push_back(std::move(panel));
    }
    std::vector<Panel> sampler_panels;
    for (std::size_t s = 0; s < sampler_results.size(); ++s) {
        Panel panel{sampler_results[s].name, sampler_results[s].reference_error, {}};
        for (std::size_t k = 0; k < all_samplers.size(); ++k)
            panel.curves.push_back({&sampler_styles()[k], &sampler_results[s].points[k]});
        sampler_panels.push_back(std::move(panel));
    }
    // The answers, before anything is written.
    for (const Panel& panel : panels) check_panel(panel);
    for (const Panel& panel : sampler_panels) check_panel(panel);
    const std::vector<std::string> checks{
        "every variant rendered the same image bit for bit in each of its runs, and every pixel is finite;",
        "every variant's error fell from the lowest sample count to the highest (none converges elsewhere);",
        "each reference's own error is at most a third of the smallest error the chart shows."};

    std::string counts;
    for (const int n : options.samples) counts += (counts.empty() ? "" : ", ") + std::to_string(n);
    write_svg(options.output_dir / "samplers.svg", sampler_panels,
              {"prism: error against time of its samplers", 
               {"relative RMSE against a " + std::to_string(options.reference_samples) +
                    "-sample independent render, the largest 0.1% of squared differences left out; " + counts +
                    " samples per pixel",
                "each scene at " + format_number(options.scale, 3) + " of its resolution; " +
                    std::to_string(tbb::info::default_concurrency()) + " threads; " + cpu_model() + "; " + date},
               "render time of the camera, wall seconds (log scale)", "--sampler", sampler_styles(),
               "Each line joins one sampler's renders at " + counts + " samples per pixel (left to right); time: median of " +
                   std::to_string(options.runs) + " interleaved runs of the camera's render (wall)."});
    if (options.samplers_only) {
        std::ofstream out(options.output_dir / "samplers.md");
        out << samplers_markdown(sampler_results, options, date);
        std::cerr << "wrote " << (options.output_dir / "samplers.svg").string() << " and .md in " << seconds_since(start)
                  << " s\n";
        return 0;
    }
    const std::vector<std::string> subtitle{
        "relative RMSE against a " + std::to_string(options.reference_samples) + "-sample MIS render; " + counts +
            " samples per pixel; render CPU time, median of " + std::to_string(options.runs) + " runs",
        std::to_string(results.front().width) + "x" + std::to_string(results.front().height) + " pixels; " +
            std::to_string(tbb::info::default_concurrency()) + " threads; " + cpu_model() + "; " + date};
    write_svg(options.output_dir / "sampling.svg", panels,
              {"prism: error against time of the path tracer's sampling strategies", subtitle,
               "render CPU time, seconds (log scale)", "RendererParams", variants(),
               "Each line joins one variant's renders at " + counts +
                   " samples per pixel (left to right); time: median of " + std::to_string(options.runs) +
                   " interleaved runs, process CPU time; sampler: " +
                   std::string(prism::sampler_name(options.sampler)) + "."});
    write_tsv(options.output_dir / "sampling.tsv", results);
    const std::string section = markdown_section(results, options, seconds_since(start), start_load, date, checks) +
                                "\n### The samplers (issue 32)\n\n" + samplers_markdown(sampler_results, options, date);
    {
        std::ofstream out(options.output_dir / "sampling.md");
        out << section;
    }
    if (!options.results.empty())
        update_marked_section(options.results, begin_marker, end_marker,
                              "## Sampling: error against time of the path tracer's strategies (issue 13, part 5)",
                              section);
    std::cerr << "wrote " << (options.output_dir / "sampling.svg").string() << ", .tsv, .md"
              << (options.results.empty() ? "" : " and the marked section of " + options.results.string()) << " in "
              << seconds_since(start) << " s\n";
    return 0;
}

}  // namespace

int main(int argc, char** argv) { return prism::bench::run_reporting_errors("prism_sampling_chart", run, argc, argv); }
