// The scene-level entry point: picks the renderer configuration a scene needs ("model no more
// than a scene needs"), builds it once, and renders every camera. The CLI, the scene suite and
// the tests all come through here, so there is one way from a scene description to images.
#pragma once

#include <prism/geometry/double_refine.hpp>
#include <prism/image/image.hpp>
#include <prism/light/area_light.hpp>
#include <prism/light/directional_light.hpp>
#include <prism/light/environment_light.hpp>
#include <prism/light/light_mesh.hpp>
#include <prism/light/light_sphere.hpp>
#include <prism/light/point_light.hpp>
#include <prism/light/spot_light.hpp>
#include <prism/render/path_tracer.hpp>
#include <prism/render/renderer.hpp>
#include <prism/scene/features.hpp>
#include <prism/scene/needs.hpp>
#include <prism/scene/scene.hpp>

#ifdef PRISM_WITH_EMBREE
#include <prism/accel/embree.hpp>
#endif

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

namespace prism {

enum class Precision { single, double_refine, double_all };

// The geometry a precision builds, as the renderer reports its configuration.
inline const char* describe(Precision precision) {
    switch (precision) {
        case Precision::single: return "float BVH, watertight triangle tests";
        case Precision::double_refine: return "float BVH, double-precision watertight triangle tests";
        case Precision::double_all: return "double BVH, watertight triangle tests";
    }
    return "?";
}

// Which index finds the hits: prism's own, or Embree 3's (accel/embree.hpp; only in programs
// built with it, PRISM_WITH_EMBREE, or that load it as a module, PRISM_EMBREE_MODULE).
enum class AcceleratorChoice { prism, embree };

inline constexpr bool embree_available =
#if defined(PRISM_WITH_EMBREE) || defined(PRISM_EMBREE_MODULE)
    true;
#else
    false;
#endif

struct RenderOptions {
    int threads = 0;                      // 0: all hardware threads
    std::optional<Precision> precision;   // empty: chosen from the scene
    double resolution_scale = 1.0;        // < 1 renders a reduced image (suite, quick checks)
    int max_samples = 0;                  // > 0 caps every camera's NumSamples (quick checks)
    // > 0 replaces every camera's NumSamples (before the cap): a reduced image compared with a
    // box-filtered noisy reference needs more samples per pixel to match its noise per area
    int samples = 0;
    BackfaceCulling backface_culling = BackfaceCulling::triangles;  // what camera rays skip from behind
    std::optional<RayOffset> ray_offset;  // empty: chosen from the scene (choose_ray_offset)
    std::uint64_t seed = 0;               // the pixels' random streams (multisampling, lights)
    std::optional<SamplerKind> sampler;   // empty: default_sampler (sampling/sampler_choice.hpp)
    AcceleratorChoice accelerator = AcceleratorChoice::prism;
};

struct CameraImage {
    std::size_t camera = 0;   // index into Scene::cameras
    std::string image_name;   // Camera::image_name
    Image image;              // linear radiance
    double seconds = 0.0;     // render time of this camera (excludes loading and BVH build)
};

// The configuration chosen for a scene, with the reason, for the CLI to print.
struct Choice {
    Precision precision = Precision::single;
    std::string reason;
};

// Float resolves 2^-24 of a coordinate. Triangles whose shortest edge spans at least 2^-12 of
// their coordinates (4096 float ulps) lose nothing in float with watertight tests; between
// 2^-16 and 2^-12 the triangle test moves to double (vertices kept in double); below 2^-16 a
// float ray origin is no longer precise to a fraction of a triangle, so everything is double.
// Spheres are tested in the renderer's Real, not refined, so a sphere below 2^-12 (a small
// sphere far from the origin: hw1's spheres_mirror moved 10^4 loses 7% of its pixels in float)
// makes everything double.
inline Choice choose_precision(const scene::PrecisionFeatures& features, const RenderOptions& options) {
    if (options.precision) return {*options.precision, "requested with --precision"};
    const auto power_of_two = [](double size) { return "2^" + std::to_string(int(std::floor(std::log2(size)))); };
    if (features.spheres_measured > 0 && features.sphere_relative_size_minimum < 0x1p-12)
        return {Precision::double_all, "the smallest sphere's radius spans " +
                                           power_of_two(features.sphere_relative_size_minimum) +
                                           " of its coordinates, below 2^-12: double throughout"};
    if (features.triangles_measured == 0)
        return {Precision::single, features.spheres_measured > 0 ? "no triangles, spheres at least 2^-12: float"
                                                                 : "no triangles: float suffices"};
    const double size = features.relative_size_percentile_1;
    const std::string measured = "the smallest triangles (1st percentile) span " + power_of_two(size) +
                                 " of their coordinates";
    if (size >= 0x1p-12) return {Precision::single, measured + ", at least 2^-12: float"};
    if (size >= 0x1p-16) return {Precision::double_refine, measured + ", below 2^-12: double-precision triangle tests"};
    return {Precision::double_all, measured + ", below 2^-16: double throughout"};
}

// The same, measuring the scene.
inline Choice choose_precision(const scene::Scene& scene, const RenderOptions& options) {
    return choose_precision(scene::measure_precision(scene), options);
}

// The renderers a scene can get in each precision: the fitted one, with point lights alone and
// no per-ray features (every hw1 and hw2 scene), or the complete one, with every light type,
// textures and motion blur. Two, not one per combination, to keep the compiled renderers few
// (each costs about 10 s of compile time on two cores); bench/ measures what the fitted one
// saves. A light type, feature or integrator is added to the shipped list below, and the
// dispatcher takes the first Config of a precision's list that covers the scene.
using PointLightSet = Lights<PointLight>;
using AllLightSet = Lights<PointLight, DirectionalLight, SpotLight, AreaLight, EnvironmentLight, LightMesh, LightSphere>;
inline constexpr Features no_features{};
inline constexpr Features all_features{.textures = true, .motion_blur = true};

// The wide BVH's width for the instruction set the renderer is compiled for. With AVX a node's
// 8 boxes are one register of floats, and the 8-wide BVH beat the 4-wide one on every batch of
// bench/intersect_bench.cpp (0.72-0.85 of its time in float, 0.69-0.98 in double). Without it
// (x86-64's SSE2 baseline, ARM's NEON) 8 floats take two registers: the 8-wide tree then took
// 1.3-2.1x the 4-wide one's time in float, and was slower than the binary BVH (bench/RESULTS.md).
#ifdef __AVX__
inline constexpr int wide_bvh_width = 8;
#else
inline constexpr int wide_bvh_width = 4;
#endif

// What each precision builds: its scalar type and its acceleration policy.
template <Precision P> struct PrecisionPolicy;
template <> struct PrecisionPolicy<Precision::single> {
    using Real = float;
    using Acceleration = WideBvh<Watertight, wide_bvh_width>;
};
template <> struct PrecisionPolicy<Precision::double_refine> {
    using Real = float;
    using Acceleration = WideBvh<DoubleRefine, wide_bvh_width>;
};
template <> struct PrecisionPolicy<Precision::double_all> {
    using Real = double;
    using Acceleration = WideBvh<Watertight, wide_bvh_width>;
};

template <class... Configs> struct ConfigList {};

// The Configs render_scene compiles for a precision, the most specialised first. The path
// tracer comes only with the complete light set and features: one more renderer per precision,
// not one per light set (DESIGN.md), and a scene without a path-traced camera never runs it.
template <Precision P, class Real = typename PrecisionPolicy<P>::Real,
          class Acceleration = typename PrecisionPolicy<P>::Acceleration>
using ShippedConfigs = ConfigList<Config<Real, Acceleration, PointLightSet, no_features, Whitted, ChosenPattern>,
                                  Config<Real, Acceleration, AllLightSet, all_features, Whitted, ChosenPattern>,
                                  Config<Real, Acceleration, AllLightSet, all_features, PathTracer, ChosenPattern>>;
#ifdef PRISM_WITH_EMBREE
// The same through Embree (--accelerator embree), which traverses in float.
using EmbreeShippedConfigs = ShippedConfigs<Precision::single, float, Embree>;
#endif

// The image size a camera renders at under RenderOptions::resolution_scale (at least 1 pixel).
inline int scaled_size(int size, double scale) { return std::max(1, int(std::lround(size * scale))); }

// Pixels render_scene will report through on_tile, for sizing a progress bar.
inline std::size_t total_pixels(const scene::Scene& scene, const RenderOptions& options) {
    std::size_t total = 0;
    for (const auto& camera : scene.cameras)
        total += std::size_t(scaled_size(camera.width, options.resolution_scale)) *
                 std::size_t(scaled_size(camera.height, options.resolution_scale));
    return total;
}

// The scene's ShadowRayEpsilon, as the course renders, unless it is too small to lift a point off
// a surface at the scene's coordinates in the chosen precision: below 64 units in the last place
// of the largest coordinate, the offset point rounds back onto (or through) the surface, and
// rays leave by their error bounds instead. The course's images are this project's accuracy
// reference and were rendered with the epsilon: it decides shadows at grazing angles (bunny:
// 102 dB with it, 36 dB with error bounds, 0.14% of pixels at shadow terminators differ).
inline RayOffset choose_ray_offset(const scene::Scene& scene, const scene::PrecisionFeatures& measured,
                                   Precision precision, const RenderOptions& options, std::string& reason) {
    if (options.ray_offset) {
        reason = "requested with --ray-offset";
        return *options.ray_offset;
    }
    const double largest = measured.largest_coordinate;
    const double unit = precision == Precision::double_all ? 0x1p-52 : 0x1p-23;
    const double ulps = scene.shadow_ray_epsilon / (unit * std::max(largest, 1e-300));
    if (largest > 0 && ulps < 64) {
        reason = "the ShadowRayEpsilon is only " + std::to_string(int(ulps)) +
                 " units in the last place of the largest coordinate";
        return RayOffset::error_bound;
    }
    reason = "the scene's ShadowRayEpsilon, as the course renders";
    return RayOffset::scene_epsilon;
}

namespace detail {

template <class C>
std::vector<CameraImage> render_with(const scene::Scene& scene, const RenderOptions& options, std::ostream& log,
                                     const std::function<void(std::size_t camera, int pixels)>& on_tile) {
    using Clock = std::chrono::steady_clock;
    const auto build_start = Clock::now();
    const Renderer<C> renderer(scene, RendererSettings{options.backface_culling, *options.ray_offset, options.seed, options.sampler});
    const double build_seconds = std::chrono::duration<double>(Clock::now() - build_start).count();
    log << "built " << renderer.geometry().instance_count() << " instances, " << renderer.geometry().triangle_count()
        << " triangles in " << build_seconds << " s\n";
    std::vector<CameraImage> images;
    for (std::size_t c = 0; c < scene.cameras.size(); ++c) {
        scene::Camera camera = scene.cameras[c];
        if (options.samples > 0) camera.num_samples = options.samples;
        if (options.max_samples > 0) camera.num_samples = std::min(camera.num_samples, options.max_samples);
        const int width = scaled_size(camera.width, options.resolution_scale);
        const int height = scaled_size(camera.height, options.resolution_scale);
        const auto start = Clock::now();
        Image image = renderer.render(camera, width, height, [&](int pixels) { on_tile(c, pixels); });
        const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
        images.push_back({c, camera.image_name, std::move(image), seconds});
    }
    return images;
}

// Renders with the first Config of the list that covers the scene's needs.
template <class... Configs>
std::vector<CameraImage> render_first_covering(ConfigList<Configs...>, const scene::Needs& needs,
                                               const scene::Scene& scene, const RenderOptions& options,
                                               std::ostream& log,
                                               const std::function<void(std::size_t camera, int pixels)>& on_tile) {
    std::optional<std::vector<CameraImage>> images;
    ((Configs::covers(needs) && (images = render_with<Configs>(scene, options, log, on_tile), true)) || ...);
    if (!images) throw std::invalid_argument("no renderer compiled into prism covers this scene");
    return std::move(*images);
}

// Programs built with PRISM_SEPARATE_RENDERERS (the project's own examples and tests, through the
// CMake target prism_shipped_renderers) take each precision's shipped renderers from that
// target's translation units, one per list (examples/renderers/), instead of compiling all of
// them in every file that renders a scene: each list costs tens of seconds of compile time, and
// apart the lists compile once and in parallel. Header-only users need no such target.
#ifdef PRISM_SEPARATE_RENDERERS
#define PRISM_SHIPPED_RENDERERS(PREFIX, LIST)                                                            \
    PREFIX template std::vector<CameraImage> render_first_covering(                                       \
        LIST, const scene::Needs&, const scene::Scene&, const RenderOptions&, std::ostream&,              \
        const std::function<void(std::size_t camera, int pixels)>&);
PRISM_SHIPPED_RENDERERS(extern, ShippedConfigs<Precision::single>)
PRISM_SHIPPED_RENDERERS(extern, ShippedConfigs<Precision::double_refine>)
PRISM_SHIPPED_RENDERERS(extern, ShippedConfigs<Precision::double_all>)
#ifdef PRISM_WITH_EMBREE
PRISM_SHIPPED_RENDERERS(extern, EmbreeShippedConfigs)
#endif
#endif

// A program built with PRISM_EMBREE_MODULE (the prism renderer) keeps its Embree renderers in a
// module it loads only for --accelerator embree: linking libembree3 cost every run 0.4-0.5 ms of
// process start (its 13,825 relocations and 168 static constructors), 1.5% of a small course
// scene. The program defines embree_module_renderer(): the module's entry point, or an exception
// saying why it cannot be loaded. Header-only users compile the Embree renderers in as before.
using RenderFunction = std::vector<CameraImage>(const scene::Needs&, const scene::Scene&, const RenderOptions&,
                                                std::ostream&, const std::function<void(std::size_t camera, int pixels)>&);
#ifdef PRISM_EMBREE_MODULE
RenderFunction* embree_module_renderer();
#endif

}  // namespace detail

// Renders every camera. `on_tile(camera, pixels)` reports progress from worker threads.
// A template, so that only a translation unit that calls it compiles the shipped renderers: as an
// inline function, every file including this header (through prism.hpp, examples/minimal among
// them) instantiated all nine for its body, used or not (examples/minimal: 960 MB and 18 of its
// 54 s of compile time on a loaded 2-core machine went to them).
template <class OnTile = std::function<void(std::size_t camera, int pixels)>>
std::vector<CameraImage> render_scene(const scene::Scene& scene, const RenderOptions& options, std::ostream& log,
                                      const OnTile& progress = [](std::size_t, int) {}) {
    const std::function<void(std::size_t camera, int pixels)> on_tile(progress);
    for (const auto& camera : scene.cameras)
        if (camera.width <= 0 || camera.height <= 0)
            throw std::invalid_argument("camera " + camera.id + ": image size must be positive");
    if (!scene.unsupported.empty()) {
        log << "warning: not rendered yet:";
        for (const auto& name : scene.unsupported) log << ' ' << name;
        log << '\n';
    }
    const int threads = options.threads > 0 ? options.threads : tbb::info::default_concurrency();
    tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    const scene::PrecisionFeatures measured = scene::measure_precision(scene);
    Choice choice = choose_precision(measured, options);
    const bool embree = options.accelerator == AcceleratorChoice::embree;
    if (embree) {
        if constexpr (!embree_available)
            throw std::invalid_argument("--accelerator embree: this prism was built without Embree 3 (libembree-dev)");
        if (choice.precision != Precision::single)
            log << "note: Embree traverses in float; prism's own accelerator would take "
                << describe(choice.precision) << " (" << choice.reason << ")\n";
        choice = {Precision::single, "Embree traverses in float"};
    }
    std::string offset_reason;
    RenderOptions chosen = options;
    chosen.ray_offset = choose_ray_offset(scene, measured, choice.precision, options, offset_reason);
    const scene::Needs needs = scene::measure_needs(scene);
    const std::string beyond = needs.beyond(Config<float, Bvh<Watertight>, PointLightSet, no_features>::meets);
    log << "configuration: "
        << (embree ? "Embree 3 BVH, prism's watertight triangle test on the triangle Embree finds"
                   : describe(choice.precision))
        << " (" << choice.reason << "); "
        << (beyond.empty() ? "point lights only, no textures or motion blur"
                           : "all light types, textures and motion blur (the scene has " + beyond + ")")
        << (needs.path_tracing ? "; path tracing (a camera asks for PathTracing)" : "")
        << "; rays leave surfaces by "
        << (*chosen.ray_offset == RayOffset::error_bound ? "their error bounds" : "the ShadowRayEpsilon") << " ("
        << offset_reason << ")\n";
#if defined(PRISM_EMBREE_MODULE)
    if (embree) return detail::embree_module_renderer()(needs, scene, chosen, log, on_tile);
#elif defined(PRISM_WITH_EMBREE)
    if (embree)
        return detail::render_first_covering(EmbreeShippedConfigs{}, needs, scene, chosen, log, on_tile);
#endif
    switch (choice.precision) {
        case Precision::single:
            return detail::render_first_covering(ShippedConfigs<Precision::single>{}, needs, scene, chosen, log, on_tile);
        case Precision::double_refine:
            return detail::render_first_covering(ShippedConfigs<Precision::double_refine>{}, needs, scene, chosen, log,
                                                 on_tile);
        case Precision::double_all:
            return detail::render_first_covering(ShippedConfigs<Precision::double_all>{}, needs, scene, chosen, log,
                                                 on_tile);
    }
    throw std::logic_error("unknown precision");
}

}  // namespace prism
