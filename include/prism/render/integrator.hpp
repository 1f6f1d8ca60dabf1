// What a renderer asks of its integrator: the radiance arriving along a camera ray, with the
// per-pixel state (`CameraPath`: the pixel's sampler and what textures need) the
// integrator defines. An integrator policy (`Whitted`, and the path tracer beside it) names the
// integrator type a Config builds and states which scenes it covers, so the dispatcher never
// renders a scene with an integrator it does not ask for.
#pragma once

#include <prism/geometry/hit.hpp>
#include <prism/geometry/ray.hpp>
#include <prism/sampling/random.hpp>
#include <prism/scene/needs.hpp>
#include <prism/scene/scene.hpp>

#include <concepts>
#include <cstdint>

namespace prism {

// Everything the Renderer calls (render/renderer.hpp), so that it never asks which of them an
// integrator has:
// - radiance: one camera ray's radiance;
// - camera rays several at a time, where batches_camera_rays(camera): their closest hits first
//   (camera_hits: bit i of the answer set where rays[i] hits, its t_max lowered to the hit),
//   then radiance_at from a ray's hit; radiance_row for a row's pixels of one sample each (up
//   to row_width, `make_path(i)` giving ray i's CameraPath), radiances_at for up to
//   prelit_width samples of one pixel, which draw from its one sampler (`path`), each after
//   `start_sample(i)` readies that sampler for ray i (a stream's samples draw in their order:
//   a no-op), where prelights(). Each gives radiance's bits for every ray: how side by side the
//   work goes is the integrator's choice.
template <class I, class Real>
concept Integrator =
    Scalar<Real> &&
    requires(const I& integrator, const Ray<Real>& ray, Ray<Real>* rays, Hit<Real>* hits, const Hit<Real>& hit,
             typename I::CameraPath& path, typename I::CameraPath (*make_path)(int), void (*start_sample)(int),
             Vec3<Real>* radiance, const scene::Camera& camera) {
        { integrator.radiance(ray, path) } -> std::same_as<Vec3<Real>>;
        { integrator.batches_camera_rays(camera) } -> std::convertible_to<bool>;
        { integrator.camera_hits(rays, hits, 1) } -> std::same_as<std::uint32_t>;
        { integrator.radiance_at(ray, hit, true, path) } -> std::same_as<Vec3<Real>>;
        { I::row_width } -> std::convertible_to<int>;
        integrator.radiance_row(rays, hits, std::uint32_t(1), 1, make_path, radiance);
        { I::prelit_width } -> std::convertible_to<int>;
        { integrator.prelights() } -> std::convertible_to<bool>;
        integrator.radiances_at(rays, hits, std::uint32_t(1), 1, path, start_sample, radiance);
    };

// An integrator policy: `P::template Type<Real, Geometry, LightSet, Textures, Environment,
// Sampler>` is the integrator a Renderer builds from its parts (Sampler: the pixel sampler its
// paths draw from, sampling/sampler.hpp); `P::covers(needs)` says whether it renders
// what the scene asks for.
template <class P>
concept IntegratorPolicy = requires(const scene::Needs& needs) {
    { P::covers(needs) } -> std::convertible_to<bool>;
};

}  // namespace prism
