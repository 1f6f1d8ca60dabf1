// The scene-level entry point: picks the renderer configuration a scene needs ("model no more
// than a scene needs"), builds it once, and renders every camera. The CLI, the scene suite and
// the tests all come through here, so there is one way from a scene description to images.
#pragma once

#include <prism/geometry/double_refine.hpp>
#include <prism/image/image.hpp>
#include <prism/light/area_light.hpp>
#include <prism/light/directional_light.hpp>
#include <prism/light/environment_light.hpp>
#include <prism/light/point_light.hpp>
#include <prism/light/spot_light.hpp>
#include <prism/render/renderer.hpp>
#include <prism/scene/features.hpp>
#include <prism/scene/scene.hpp>

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

struct RenderOptions {
    int threads = 0;                      // 0: all hardware threads
    std::optional<Precision> precision;   // empty: chosen from the scene
    double resolution_scale = 1.0;        // < 1 renders a reduced image (suite, quick checks)
    int max_samples = 0;                  // > 0 caps every camera's NumSamples (quick checks)
    BackfaceCulling backface_culling = BackfaceCulling::flat_triangles;  // what camera rays skip from behind
    std::optional<RayOffset> ray_offset;  // empty: chosen from the scene (choose_ray_offset)
    std::uint64_t seed = 0;               // the pixels' random streams (multisampling, lights)
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
inline Choice choose_precision(const scene::Scene& scene, const RenderOptions& options) {
    if (options.precision) return {*options.precision, "requested with --precision"};
    const scene::PrecisionFeatures features = scene::measure_precision(scene);
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

// The two renderers a scene can get in each precision: the fitted one, with point lights alone
// and no per-ray features (every hw1 and hw2 scene), or the complete one, with every light type,
// textures and motion blur. Two, not one per combination, to keep the compiled renderers few
// (each costs about 20 s of compile time on two cores); bench/ measures what the fitted one
// saves.
using PointLightSet = Lights<PointLight>;
using AllLightSet = Lights<PointLight, DirectionalLight, SpotLight, AreaLight, EnvironmentLight>;
inline constexpr Features no_features{};
inline constexpr Features all_features{.textures = true, .motion_blur = true};

// Every light the scene describes, of any type. A light type added to scene::Scene must be
// counted here, so that a renderer whose light set lacks it refuses the scene instead of
// leaving the light out.
inline std::size_t scene_light_count(const scene::Scene& scene) {
    return scene.point_lights.size() + scene.directional_lights.size() + scene.spot_lights.size() +
           scene.area_lights.size() + scene.environment_lights.size();
}

// Whether the scene needs more than the fitted renderer: other lights than point lights,
// textures, or moving objects. Returns what it needs, for the log; empty when nothing.
inline std::string complete_renderer_reason(const scene::Scene& scene) {
    std::string reason;
    const auto add = [&](bool needed, const char* what) {
        if (!needed) return;
        reason += reason.empty() ? "" : ", ";
        reason += what;
    };
    add(!scene.directional_lights.empty(), "directional lights");
    add(!scene.spot_lights.empty(), "spot lights");
    add(!scene.area_lights.empty(), "area lights");
    add(!scene.environment_lights.empty(), "environment lights");
    add(!scene.textures.empty(), "textures");
    const auto moving = [](const auto& objects) {
        return std::any_of(objects.begin(), objects.end(),
                           [](const auto& object) { return object.motion != glm::dvec3(0.0); });
    };
    add(moving(scene.meshes) || moving(scene.spheres) || moving(scene.mesh_instances), "motion blur");
    return reason;
}

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
inline RayOffset choose_ray_offset(const scene::Scene& scene, Precision precision, const RenderOptions& options,
                                   std::string& reason) {
    if (options.ray_offset) {
        reason = "requested with --ray-offset";
        return *options.ray_offset;
    }
    const double largest = scene::measure_precision(scene).largest_coordinate;
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
    if (C::LightTypes::count_in(scene) != scene_light_count(scene))
        throw std::invalid_argument("the scene has " + std::to_string(scene_light_count(scene)) +
                                    " lights, of which this renderer's light set can render only " +
                                    std::to_string(C::LightTypes::count_in(scene)));
    using Clock = std::chrono::steady_clock;
    const auto build_start = Clock::now();
    const Renderer<C> renderer(scene, RendererSettings{options.backface_culling, *options.ray_offset, options.seed});
    const double build_seconds = std::chrono::duration<double>(Clock::now() - build_start).count();
    log << "built " << renderer.geometry().instance_count() << " instances, " << renderer.geometry().triangle_count()
        << " triangles in " << build_seconds << " s\n";
    std::vector<CameraImage> images;
    for (std::size_t c = 0; c < scene.cameras.size(); ++c) {
        scene::Camera camera = scene.cameras[c];
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

template <Scalar Real, class Acceleration>
std::vector<CameraImage> render_fitted(const scene::Scene& scene, const RenderOptions& options, std::ostream& log,
                                       const std::function<void(std::size_t camera, int pixels)>& on_tile) {
    if (!complete_renderer_reason(scene).empty())
        return render_with<Config<Real, Acceleration, AllLightSet, all_features>>(scene, options, log, on_tile);
    return render_with<Config<Real, Acceleration, PointLightSet, no_features>>(scene, options, log, on_tile);
}

}  // namespace detail

// Renders every camera. `on_tile(camera, pixels)` reports progress from worker threads.
inline std::vector<CameraImage> render_scene(
    const scene::Scene& scene, const RenderOptions& options, std::ostream& log,
    const std::function<void(std::size_t camera, int pixels)>& on_tile = [](std::size_t, int) {}) {
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
    const Choice choice = choose_precision(scene, options);
    std::string offset_reason;
    RenderOptions chosen = options;
    chosen.ray_offset = choose_ray_offset(scene, choice.precision, options, offset_reason);
    const std::string complete = complete_renderer_reason(scene);
    log << "configuration: " << describe(choice.precision) << " (" << choice.reason << "); "
        << (complete.empty() ? "point lights only, no textures or motion blur"
                             : "all light types, textures and motion blur (the scene has " + complete + ")")
        << "; rays leave surfaces by "
        << (*chosen.ray_offset == RayOffset::error_bound ? "their error bounds" : "the ShadowRayEpsilon") << " ("
        << offset_reason << ")\n";
    switch (choice.precision) {
        case Precision::single:
            return detail::render_fitted<float, Bvh<Watertight>>(scene, chosen, log, on_tile);
        case Precision::double_refine:
            return detail::render_fitted<float, Bvh<DoubleRefine>>(scene, chosen, log, on_tile);
        case Precision::double_all:
            return detail::render_fitted<double, Bvh<Watertight>>(scene, chosen, log, on_tile);
    }
    throw std::logic_error("unknown precision");
}

}  // namespace prism
