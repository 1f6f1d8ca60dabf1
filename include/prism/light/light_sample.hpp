// What a light tells a shading point: where the light comes from, how far the shadow ray must
// reach, and the radiance-like quantity arriving (irradiance on a surface facing the light).
// Lights that are not a point or a direction (area, environment) are sampled: `u` is a uniform
// point of [0, 1)^2 from the pixel's random stream, and the sample's radiance is already the
// Monte Carlo estimate (divided by the probability density of the chosen direction), so the
// integrator treats every light alike.
#pragma once

#include <prism/math/vector.hpp>
#include <prism/scene/needs.hpp>

#include <concepts>
#include <vector>

namespace prism {

template <Scalar Real>
struct LightSample {
    Vec3<Real> direction{0};  // unit, from the shading point towards the light
    Real distance = 0;        // shadow rays test (epsilon, distance)
    Vec3<Real> radiance{0};   // arriving at the point, before the cosine and the BRDF
    // The solid-angle density the direction was drawn with, for lights that rays can also hit
    // (object lights), so an integrator can weigh this sample against a BRDF sample (multiple
    // importance sampling). Zero for lights no ray can hit: points, spots, directions, and the
    // lights prism samples only from the shading point (area, environment).
    Real pdf = 0;
};

// Where a light is seen from: the shading point and its unit normal on the side the ray came
// from (hemisphere samplers need it; punctual lights ignore it).
template <Scalar Real>
struct ShadingFrame {
    Vec3<Real> position{0};
    Vec3<Real> normal{0, 0, 1};
};

// A light type: built from the plain scene, sampled from a shading point. No virtual calls:
// LightSet loops over each type's vector with a fold expression.
template <class L, class Real>
concept Light = Scalar<Real> && requires(const L& light, const ShadingFrame<Real>& at, const Vec2<Real>& u,
                                         const scene::Scene& scene) {
    { light.sample(at, u) } -> std::same_as<LightSample<Real>>;
    { L::from_scene(scene) } -> std::same_as<std::vector<L>>;
    { L::kind } -> std::convertible_to<scene::LightKind>;
};

// Whether a light type is sampled without a draw: a point, a direction or a spot (sample(at)
// alone). An integrator skips such a light's two numbers instead of drawing them (skip<Real>(2)):
// a stream steps past them as if drawn, so every later draw is the one it was, and a sampler
// with dimensions works nothing out for them (a Sobol' pixel's pair of a dimension is 16 lanes'
// points at once, which nothing would read).
template <class L, class Real>
inline constexpr bool sampled_without_draws = requires(const L& light, const ShadingFrame<Real>& at) { light.sample(at); };

}  // namespace prism
