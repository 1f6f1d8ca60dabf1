// A pixel as the Renderer renders it, made the slow way: the pixel's camera samples drawn from
// its sampler (the centre sample for one, as Renderer::one_sample_row takes it), each traced
// alone with the integrator's own radiance, in their order, and summed with
// the filter weights as Renderer::pixel sums them. Tests compare every batched route's pixels
// with it, bit for bit.
#pragma once

#include <prism/camera/pixel_sampler.hpp>
#include <prism/camera/thin_lens_camera.hpp>
#include <prism/render/renderer.hpp>

#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

namespace prism_test {

// A Renderer's parts, made as its constructor makes them, for a test that calls its integrator
// itself. The integrator holds references into the other parts: the whole is neither copied
// nor moved.
template <class Whole>
struct RendererParts {
    using Real = typename Whole::Real;

    RendererParts(const prism::scene::Scene& world, const prism::RendererSettings& settings)
        : geometry(world), lights(world), materials(materials_of(world)), textures(world),
          environment(environment_of(lights)),
          integrator(geometry, lights, materials, textures, environment, prism::Vec3<Real>(world.ambient_light),
                     prism::Vec3<Real>(world.background_color),
                     prism::IntegratorSettings{world.max_recursion_depth, world.shadow_ray_epsilon, settings.ray_offset,
                                               settings.backface_culling}) {}
    RendererParts(const RendererParts&) = delete;
    RendererParts& operator=(const RendererParts&) = delete;

    const typename Whole::Geometry geometry;
    const typename Whole::LightSetT lights;
    const std::vector<prism::Material<Real>> materials;
    const typename Whole::TexturesT textures;
    const typename Whole::EnvironmentT environment;
    const typename Whole::Integrator integrator;

private:
    static std::vector<prism::Material<Real>> materials_of(const prism::scene::Scene& world) {
        std::vector<prism::Material<Real>> list;
        for (const prism::scene::Material& material : world.materials) list.emplace_back(material);
        return list;
    }
    static typename Whole::EnvironmentT environment_of(const typename Whole::LightSetT& lights) {
        if constexpr (Whole::environment_lights)
            return typename Whole::EnvironmentT(*lights.template of_type<prism::EnvironmentLight>());
        else
            return typename Whole::EnvironmentT{};
    }
};

// `make_path(sampler, pixel_uv, spread)`: the integrator's CameraPath for the pixel, drawing from
// `sampler`, the pixel's sampler of `pattern` (the render's, as make_pattern makes it). A stream
// (prism::streamed) draws the camera samples first and the paths after them in their order;
// any other sampler gives sample i its camera sample from its first dimensions
// (prism::camera_sample) and its path the dimensions after them.
template <class Real, class Integrator, class Pattern, class MakePath>
glm::vec3 one_by_one_pixel(const Integrator& integrator, const prism::ThinLensCamera<Real>& lens,
                           const prism::scene::Camera& camera, const Pattern& pattern, int count, int x, int y,
                           std::uint64_t seed, MakePath make_path) {
    using Sampler = std::remove_reference_t<decltype(std::declval<typename Integrator::CameraPath&>().sampler)>;
    const prism::Vec2<Real> pixel_uv((Real(x) + Real(0.5)) / Real(lens.width()), (Real(y) + Real(0.5)) / Real(lens.height()));
    prism::Vec3<Real> sum(0);
    Real weights = 0;
    const auto add = [&](const prism::CameraSample<Real>& sample, auto& path) {
        const prism::Ray<Real> ray = lens.ray(Real(x) + sample.pixel.x, Real(y) + sample.pixel.y, sample.lens, sample.time);
        const Real weight = count == 1 ? Real(1) : prism::filter_weight(camera.filter, sample.pixel);
        sum += weight * integrator.radiance(ray, path);
        weights += weight;
    };
    if (!prism::streamed(pattern)) {
        Sampler sampler = pattern.for_pixel(x, y);
        auto path = make_path(sampler, pixel_uv, lens.pixel_spread());
        for (int i = 0; i < count; ++i) {
            sampler.start_sample(i);
            add(prism::camera_sample<Real>(sampler, count == 1), path);
        }
        return glm::vec3(sum / weights);
    }
    if constexpr (std::is_constructible_v<Sampler, prism::IndependentSampler>) {
        prism::Random random = prism::Random::for_pixel(x, y, seed);
        std::vector<prism::CameraSample<Real>> samples;
        std::vector<prism::Vec2<Real>> strata;
        if (count == 1) samples = {prism::centre_sample<Real>(random)};
        else prism::camera_samples(count, random, samples, strata);
        Sampler sampler(prism::IndependentSampler{random});
        auto path = make_path(sampler, pixel_uv, lens.pixel_spread());
        for (const prism::CameraSample<Real>& sample : samples) add(sample, path);
    }
    return glm::vec3(sum / weights);
}

}  // namespace prism_test
