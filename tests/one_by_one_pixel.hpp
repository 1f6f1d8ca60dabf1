// A pixel as the Renderer renders it, made the slow way: the pixel's camera samples drawn from
// its stream (the centre sample for one, as Renderer::one_sample_row takes it), each traced
// alone with the integrator's own radiance, in their order on that one stream, and summed with
// the filter weights as Renderer::pixel sums them. Tests compare every batched route's pixels
// with it, bit for bit.
#pragma once

#include <prism/camera/pixel_sampler.hpp>
#include <prism/camera/thin_lens_camera.hpp>
#include <prism/render/renderer.hpp>

#include <cstdint>
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

// `make_path(random, pixel_uv, spread)`: the integrator's CameraPath for the pixel.
template <class Real, class Integrator, class MakePath>
glm::vec3 one_by_one_pixel(const Integrator& integrator, const prism::ThinLensCamera<Real>& lens,
                           const prism::scene::Camera& camera, int count, int x, int y, std::uint64_t seed,
                           MakePath make_path) {
    prism::Random random = prism::Random::for_pixel(x, y, seed);
    auto path = make_path(random,
                          prism::Vec2<Real>((Real(x) + Real(0.5)) / Real(lens.width()),
                                            (Real(y) + Real(0.5)) / Real(lens.height())),
                          lens.pixel_spread());
    std::vector<prism::CameraSample<Real>> samples;
    std::vector<prism::Vec2<Real>> strata;
    if (count == 1) samples = {prism::centre_sample<Real>(random)};
    else prism::camera_samples(count, random, samples, strata);
    prism::Vec3<Real> sum(0);
    Real weights = 0;
    for (const prism::CameraSample<Real>& sample : samples) {
        const prism::Ray<Real> ray = lens.ray(Real(x) + sample.pixel.x, Real(y) + sample.pixel.y, sample.lens, sample.time);
        const Real weight = count == 1 ? Real(1) : prism::filter_weight(camera.filter, sample.pixel);
        sum += weight * integrator.radiance(ray, path);
        weights += weight;
    }
    return glm::vec3(sum / weights);
}

}  // namespace prism_test
