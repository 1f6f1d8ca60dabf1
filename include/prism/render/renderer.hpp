// The renderer a Config composes: geometry built in the Config's precision with its
// acceleration policy, its light set, textures and motion blur if the Config asks for them, the
// course's integrator, and tiles of pixels rendered in parallel with TBB into an HDR image.
// Every pixel draws its samples from its own sampler (the Config's sampler policy,
// sampling/sampler_choice.hpp), keyed by the pixel and the seed, so an image is bit-identical
// whatever the number of threads.
#pragma once

#include <prism/camera/pixel_sampler.hpp>
#include <prism/camera/thin_lens_camera.hpp>
#include <prism/geometry/scene_geometry.hpp>
#include <prism/image/image.hpp>
#include <prism/io/limits.hpp>
#include <prism/light/environment_light.hpp>
#include <prism/math/denormals.hpp>
#include <prism/memory/unconstructed.hpp>
#include <prism/render/config.hpp>
#include <prism/render/stored_whole.hpp>
#include <prism/texture/texture_set.hpp>

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace prism {

struct RendererSettings {
    BackfaceCulling backface_culling = BackfaceCulling::triangles;  // what camera rays skip from behind
    RayOffset ray_offset = RayOffset::scene_epsilon;
    std::uint64_t seed = 0;       // selects the pixels' random streams
    std::optional<SamplerKind> sampler;  // empty: the Config's sampler policy's own (default_sampler)
};

template <class C>
class Renderer {
public:
    using Real = typename C::Real;
    static constexpr Features features = C::features;
    using Geometry = typename GeometryOf<typename C::Acceleration, Real, features.motion_blur>::type;
    using LightSetT = typename C::LightTypes::template Set<Real>;
    using TexturesT = std::conditional_t<features.textures, TextureSet<Real>, NoTextures<Real>>;
    static constexpr bool environment_lights = C::LightTypes::template contains<EnvironmentLight>;
    using EnvironmentT = std::conditional_t<environment_lights, EnvironmentBackground<Real>, NoEnvironment<Real>>;
    using Pattern = typename C::SamplerPolicy;
    using PixelSamplerT = decltype(std::declval<const Pattern&>().for_pixel(0, 0));
    using Integrator =
        typename C::IntegratorPolicy::template Type<Real, Geometry, LightSetT, TexturesT, EnvironmentT, PixelSamplerT>;
    static_assert(prism::Integrator<Integrator, Real>);

    static constexpr int tile_size = 16;

    explicit Renderer(const scene::Scene& scene, const RendererSettings& settings = {})
        : geometry_(check_features(scene)), lights_(scene), materials_(convert_materials(scene)), textures_(scene),
          environment_(make_environment(lights_)), settings_(check_sampler(settings)),
          integrator_(geometry_, lights_, materials_, textures_, environment_, Vec3<Real>(scene.ambient_light),
                      Vec3<Real>(scene.background_color),
                      IntegratorSettings{scene.max_recursion_depth, scene.shadow_ray_epsilon, settings.ray_offset,
                                         settings.backface_culling}),
          moving_(features.motion_blur && scene::has_moving_objects(scene)) {}

    // A renderer holds references into itself (the integrator into geometry and lights).
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    const Geometry& geometry() const { return geometry_; }
    const LightSetT& lights() const { return lights_; }

    // Renders `camera` at width x height (0: the camera's own resolution). `on_tile(pixels)` is
    // called from worker threads after each finished tile, for progress reporting.
    template <class OnTile = void (*)(int)>
    Image render(const scene::Camera& camera, int width = 0, int height = 0, OnTile on_tile = [](int) {}) const {
        if (width <= 0) width = camera.width;
        if (height <= 0) height = camera.height;
        check_image(camera, width, height);
        const ThinLensCamera<Real> lens(camera, width, height);
        const int count = std::max(1, camera.num_samples);
        const Real spread = lens.pixel_spread();
        const Pattern pattern = make_pattern<Pattern>({count, width, height, settings_.seed, settings_.sampler});
        Image image(width, height, Image::Unfilled{});  // every pixel is written below
        tbb::parallel_for(tbb::blocked_range2d<int>(0, height, tile_size, 0, width, tile_size),
                          [&](const tbb::blocked_range2d<int>& tile) {
                              {
                                  const FlushDenormals flush;  // math/denormals.hpp; restored before on_tile
                                  PixelScratch scratch;
                                  for (int y = tile.rows().begin(); y < tile.rows().end(); ++y) {
                                      if (count == 1) {
                                          one_sample_row(lens, camera, pattern, spread, y, tile.cols().begin(),
                                                         tile.cols().end(), image);
                                          continue;
                                      }
                                      for (int x = tile.cols().begin(); x < tile.cols().end(); ++x)
                                          image(x, y) = pixel(lens, camera, pattern, spread, count, x, y, scratch);
                                  }
                              }
                              on_tile(int(tile.rows().size() * tile.cols().size()));
                          });
        return image;
    }

    // Radiance along one ray (unit direction) at shutter instant ray.time, for tests and tools;
    // lights and roughness are sampled from the first sample of pixel (0, 0), from its first
    // dimension.
    Vec3<Real> radiance(const Ray<Real>& ray) const {
        const FlushDenormals flush;  // as render() computes it
        const Pattern pattern = make_pattern<Pattern>({1, 1, 1, settings_.seed, settings_.sampler});
        PixelSamplerT sampler = pattern.for_pixel(0, 0);  // reads the pattern's tables
        sampler.start_sample(0);
        typename Integrator::CameraPath path{sampler, Vec2<Real>(Real(0.5))};
        return integrator_.radiance(ray, path);
    }

private:
    // Whether the Pattern can be a stream (IndependentPattern, ChosenPattern): only those
    // compile the streamed routes, which draw the camera samples from a Random first.
    static constexpr bool can_stream = std::is_constructible_v<PixelSamplerT, IndependentSampler>;

    // Which of the camera's dimensions the render reads (camera_sample).
    CameraReads camera_reads(const ThinLensCamera<Real>& lens) const { return {lens.has_aperture(), moving_}; }

    // The path a camera ray of pixel (x, y) carries, drawing from `sampler`. `spread` is
    // lens.pixel_spread(), computed once a render: two square roots and a division, which each
    // pixel waited for before its trace (a fifth of the per-row samples on hw1 simple_reflectance
    // once the rows were batched).
    typename Integrator::CameraPath camera_path(const ThinLensCamera<Real>& lens, const scene::Camera& camera,
                                                Real spread, PixelSamplerT& sampler, int x, int y) const {
        typename Integrator::CameraPath path{
            sampler, Vec2<Real>((Real(x) + Real(0.5)) / Real(lens.width()), (Real(y) + Real(0.5)) / Real(lens.height())),
            spread};
        // Integrators that render cameras differently (the path tracer's RendererParams) learn
        // the camera's choice here.
        if constexpr (requires { path.renderer; }) path.renderer = camera.renderer;
        return path;
    }

    // The pixels [begin, end) of row y with one sample each (every hw1-hw2 camera): first every
    // pixel's stream and camera ray, then every trace. The sample is the centre (centre_sample,
    // as camera_samples(1, ...) draws it), which both filters weigh exactly 1 (exp(-0)), so the
    // weight is not computed: the same sum and division as for any count, the same bits.
    // A pixel's stream (two rounds of mix_bits, three draws) and its ray (a square root and a
    // division) depend on no other pixel's, so the core overlaps them from pixel to pixel,
    // where one pixel at a time waited for them before its trace (the per-pixel lambda was
    // 13-14% of hw1 simple_reflectance's samples, an eighth of them on the instruction after the
    // ray's division).
    // With a sampler that is not a stream, each pixel's sampler gives its sample 0's lens point
    // and time from the camera's dimensions (camera_sample), at the pixel's centre.
    void one_sample_row(const ThinLensCamera<Real>& lens, const scene::Camera& camera, const Pattern& pattern,
                        Real spread, int y, int begin, int end, Image& image) const {
        constexpr int batch = tile_size;
        Unconstructed<PixelSamplerT, batch> samplers;
        std::array<Ray<Real>, batch> rays;
        const bool stream = streamed(pattern);
        for (int start = begin; start < end; start += batch) {
            const int n = std::min(batch, end - start);
            if (!stream) {
                for (int i = 0; i < n; ++i) {
                    const int x = start + i;
                    PixelSamplerT& sampler = samplers.make(std::size_t(i), pattern.for_pixel(x, y));
                    sampler.start_sample(0);
                    const CameraSample<Real> sample = camera_sample<Real>(sampler, true, camera_reads(lens));
                    rays[std::size_t(i)] = stored_whole(
                        lens.ray(Real(x) + sample.pixel.x, Real(y) + sample.pixel.y, sample.lens, sample.time));
                }
            } else if constexpr (can_stream) {
                std::array<Random, batch> streams;
                if (!lens.has_aperture()) {
                    // A pinhole, which never reads the lens point: the row's streams stepped past
                    // the lens's two draws, and its rays, lane by lane
                    // (Random::for_row, ThinLensCamera::centre_rays), the time drawn between them,
                    // as centre_sample draws it. Lanes past the row's end are made and not used.
                    std::array<Real, batch> times;
                    Random::for_row<Real>(start, y, settings_.seed, 2, streams, times);
                    lens.centre_rays(start, y, times, rays);
                } else {
                    for (int i = 0; i < n; ++i) {
                        const int x = start + i;
                        streams[std::size_t(i)] = Random::for_pixel(x, y, settings_.seed);
                        const CameraSample<Real> sample = centre_sample<Real>(streams[std::size_t(i)]);
                        rays[std::size_t(i)] = stored_whole(
                            lens.ray(Real(x) + sample.pixel.x, Real(y) + sample.pixel.y, sample.lens, sample.time));
                    }
                }
                for (int i = 0; i < n; ++i) samplers.make(std::size_t(i), IndependentSampler(streams[std::size_t(i)]));
            }
            // Where the integrator batches camera rays, the row's closest hits first, then its
            // shading (radiance_row: the row's shadow rays side by side where the integrator can).
            if (integrator_.batches_camera_rays(camera)) {
                static_assert(Integrator::row_width >= batch);
                std::array<Hit<Real>, batch> hits;
                const std::uint32_t found = integrator_.camera_hits(rays.data(), hits.data(), n);
                const auto make_path = [&](int i) {
                    return camera_path(lens, camera, spread, samplers[std::size_t(i)], start + i, y);
                };
                std::array<Vec3<Real>, batch> radiance;
                integrator_.radiance_row(rays.data(), hits.data(), found, n, make_path, radiance.data());
                for (int i = 0; i < n; ++i) image(start + i, y) = one_sample_pixel(radiance[std::size_t(i)]);
                continue;
            }
            for (int i = 0; i < n; ++i) {
                const int x = start + i;
                typename Integrator::CameraPath path = camera_path(lens, camera, spread, samplers[std::size_t(i)], x, y);
                image(x, y) = one_sample_pixel(integrator_.radiance(rays[std::size_t(i)], path));
            }
        }
    }

    // A one-sample pixel's value: pixel()'s weighted mean with the one weight 1, whose product
    // and division are exact. What remains is the sum's start at +0, which turns a radiance of
    // -0 into +0 as pixel() does.
    static glm::vec3 one_sample_pixel(const Vec3<Real>& radiance) { return glm::vec3(Vec3<Real>(0) + radiance); }

    // What a tile's multi-sample pixels reuse, so that no pixel allocates.
    struct PixelScratch {
        std::vector<CameraSample<Real>> samples;
        std::vector<Vec2<Real>> strata;
        std::vector<Ray<Real>> rays;
        std::vector<Real> weights;
    };

    // A pixel of several samples: every sample's ray and filter weight first, then the traces.
    // As in one_sample_row, the rays and weights depend on no trace (and draw nothing), so
    // their divisions, square roots and exponentials overlap, and the sums are the same.
    // A stream (streamed(pattern)) draws every camera sample first, stratified across the pixel
    // (camera_samples), and the samples' paths then go on drawing from it in their order. Any
    // other sampler gives sample i its camera sample and its path's numbers from its own
    // dimensions (start_sample(i)), so each sample's path starts past the camera's dimensions.
    glm::vec3 pixel(const ThinLensCamera<Real>& lens, const scene::Camera& camera, const Pattern& pattern, Real spread,
                    int count, int x, int y, PixelScratch& scratch) const {
        const scene::PixelFilter filter = camera.filter;
        const bool stream = streamed(pattern);
        PixelSamplerT sampler = [&] {
            if constexpr (can_stream) {
                if (stream) {
                    Random random = Random::for_pixel(x, y, settings_.seed);
                    camera_samples(count, random, scratch.samples, scratch.strata, camera_reads(lens));
                    return PixelSamplerT(IndependentSampler(random));
                }
            }
            PixelSamplerT pixel_sampler = pattern.for_pixel(x, y);
            scratch.samples.resize(std::size_t(count));
            for (int i = 0; i < count; ++i) {
                pixel_sampler.start_sample(i);
                scratch.samples[std::size_t(i)] = camera_sample<Real>(pixel_sampler, false, camera_reads(lens));
            }
            return pixel_sampler;
        }();
        const auto start_sample = [&](std::size_t i) {
            if (stream) return;
            sampler.start_sample(int(i));
            sampler.seek(camera_dimensions);
        };
        typename Integrator::CameraPath path = camera_path(lens, camera, spread, sampler, x, y);
        const std::size_t n = scratch.samples.size();
        scratch.rays.resize(n);
        scratch.weights.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const CameraSample<Real>& sample = scratch.samples[i];
            scratch.rays[i] =
                stored_whole(lens.ray(Real(x) + sample.pixel.x, Real(y) + sample.pixel.y, sample.lens, sample.time));
            scratch.weights[i] = filter_weight(filter, sample.pixel);
        }
        Vec3<Real> sum(0);
        Real weights = 0;
        // Where the integrator finds camera hits apart from shading (camera_hits), the
        // samples' closest hits come first, up to 32 at a time, then each sample's radiance
        // from its hit, in the samples' order: the hits radiance's own intersection finds and
        // the same draws, so the same sum. The traversals then follow one another without a
        // shading in between (hw4 VeachAjar's 16 samples a pixel).
        if (integrator_.batches_camera_rays(camera)) {
            constexpr std::size_t batch = 32;
            Unconstructed<Hit<Real>, batch> hits;
            for (std::size_t first = 0; first < n; first += batch) {
                const int count = int(std::min(batch, n - first));
                Ray<Real>* const rays = scratch.rays.data() + first;
                const std::uint32_t found = integrator_.camera_hits(rays, hits.data(), count);
                // Where the integrator samples the lights that draw nothing for several samples
                // first (prelights), their shadow rays go side by side, and each sample then
                // draws from its own start (start_sample; a stream's samples in their order).
                // Only for a stream, the hw3-hw5 ray-traced scenes took up to 1.20 times as long
                // with the sobol sampler (bench/RESULTS.md, "The samplers").
                if (integrator_.prelights()) {
                    constexpr int width = Integrator::prelit_width;
                    std::array<Vec3<Real>, width> radiance;
                    for (int part = 0; part < count; part += width) {
                        const int n = std::min(width, count - part);
                        const std::size_t base = first + std::size_t(part);
                        integrator_.radiances_at(rays + part, hits.data() + part, found >> part, n, path,
                                                 [&](int i) { start_sample(base + std::size_t(i)); }, radiance.data());
                        for (int i = 0; i < n; ++i) {
                            const Real weight = scratch.weights[first + std::size_t(part + i)];
                            sum += weight * radiance[std::size_t(i)];
                            weights += weight;
                        }
                    }
                    continue;
                }
                for (int i = 0; i < count; ++i) {
                    const Real weight = scratch.weights[first + std::size_t(i)];
                    start_sample(first + std::size_t(i));
                    sum += weight * integrator_.radiance_at(rays[i], hits[std::size_t(i)], (found >> i) & 1, path);
                    weights += weight;
                }
            }
            return glm::vec3(sum / weights);
        }
        for (std::size_t i = 0; i < n; ++i) {
            start_sample(i);
            sum += scratch.weights[i] * integrator_.radiance(scratch.rays[i], path);
            weights += scratch.weights[i];
        }
        return glm::vec3(sum / weights);
    }

    // A scene built in code meets the limits the loaders hold files to (io/limits.hpp): the ray
    // tracer recurses once per bounce on a worker's stack, so a depth beyond the stack-safe one
    // would crash, not fail.
    static void check_limits(const scene::Scene& scene) {
        if (scene.max_recursion_depth < 0 || scene.max_recursion_depth > io::stack_safe_recursion_depth)
            throw std::invalid_argument("MaxRecursionDepth " + std::to_string(scene.max_recursion_depth) +
                                        " is outside [0, " + std::to_string(io::stack_safe_recursion_depth) +
                                        "], the depth the renderer's stack is known to hold");
    }

    // An image the film could not hold, or a sample count past the loaders' limit, is refused
    // before anything is allocated for it.
    static void check_image(const scene::Camera& camera, int width, int height) {
        const std::string name = "camera " + camera.id + ": ";
        if (width < 1 || height < 1 || width > io::max_image_side || height > io::max_image_side ||
            std::int64_t(width) * std::int64_t(height) > io::max_image_pixels)
            throw std::invalid_argument(name + "an image of " + std::to_string(width) + "x" + std::to_string(height) +
                                        " pixels is outside the limits (" + std::to_string(io::max_image_side) +
                                        " a side, " + std::to_string(io::max_image_pixels) + " in all)");
        if (camera.num_samples > io::max_samples_per_pixel)
            throw std::invalid_argument(name + std::to_string(camera.num_samples) +
                                        " samples per pixel are more than the limit of " +
                                        std::to_string(io::max_samples_per_pixel));
    }

    // A sampler kind that the Config's sampler policy does not hold is refused when the renderer
    // is made (make_pattern), not at its first render.
    static const RendererSettings& check_sampler(const RendererSettings& settings) {
        (void)make_pattern<Pattern>({1, 1, 1, settings.seed, settings.sampler});
        return settings;
    }

    // A renderer compiled without a light kind, a feature or an integrator the scene needs
    // refuses the scene, rather than rendering it wrong.
    static const scene::Scene& check_features(const scene::Scene& scene) {
        check_limits(scene);
        const scene::Needs needs = scene::measure_needs(scene);
        if (!C::covers(needs)) {
            std::string missing = needs.beyond(C::meets);
            throw std::invalid_argument("the scene needs " + (missing.empty() ? "another integrator" : missing) +
                                        ", which this renderer was compiled without");
        }
        return scene;
    }

    // The environment lights' images are also the background for rays that escape; the
    // background shares them rather than loading them again.
    static EnvironmentT make_environment(const LightSetT& lights) {
        if constexpr (environment_lights) return EnvironmentT(*lights.template of_type<EnvironmentLight>());
        else return EnvironmentT{};
    }

    static std::vector<Material<Real>> convert_materials(const scene::Scene& scene) {
        std::vector<Material<Real>> materials;
        for (const auto& material : scene.materials) materials.emplace_back(material);
        return materials;
    }

    Geometry geometry_;
    LightSetT lights_;
    std::vector<Material<Real>> materials_;
    TexturesT textures_;
    EnvironmentT environment_;
    RendererSettings settings_;
    Integrator integrator_;
    bool moving_;  // whether a ray's shutter instant matters: something in the scene moves
};

}  // namespace prism
