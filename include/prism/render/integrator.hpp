// What a renderer asks of its integrator: the radiance arriving along a camera ray, with the
// per-pixel state (`CameraPath`: the pixel's random stream and what textures need) the
// integrator defines. An integrator policy (`Whitted`, and the path tracer beside it) names the
// integrator type a Config builds and states which scenes it covers, so the dispatcher never
// renders a scene with an integrator it does not ask for.
#pragma once

#include <prism/geometry/ray.hpp>
#include <prism/sampling/random.hpp>
#include <prism/scene/needs.hpp>

#include <concepts>

namespace prism {

template <class I, class Real>
concept Integrator = Scalar<Real> && requires(const I& integrator, const Ray<Real>& ray,
                                              typename I::CameraPath& path) {
    { integrator.radiance(ray, path) } -> std::same_as<Vec3<Real>>;
};

// An integrator policy: `P::template Type<Real, Geometry, LightSet, Textures, Environment>` is
// the integrator a Renderer builds from its parts; `P::covers(needs)` says whether it renders
// what the scene asks for.
template <class P>
concept IntegratorPolicy = requires(const scene::Needs& needs) {
    { P::covers(needs) } -> std::convertible_to<bool>;
};

}  // namespace prism
