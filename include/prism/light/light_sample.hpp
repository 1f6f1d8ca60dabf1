// What a light tells a shading point: where the light comes from, how far the shadow ray must
// reach, and the radiance-like quantity arriving (irradiance on a surface facing the light).
#pragma once

#include <prism/math/vector.hpp>
#include <prism/scene/scene.hpp>

#include <concepts>
#include <vector>

namespace prism {

template <Scalar Real>
struct LightSample {
    Vec3<Real> direction{0};  // unit, from the shading point towards the light
    Real distance = 0;        // shadow rays test (epsilon, distance)
    Vec3<Real> radiance{0};   // arriving at the point, before the cosine and the BRDF
};

// A light type: built from the plain scene, sampled from a shading point. No virtual calls:
// LightSet loops over each type's vector with a fold expression.
template <class L, class Real>
concept Light = Scalar<Real> && requires(const L& light, const Vec3<Real>& point, const scene::Scene& scene) {
    { light.sample(point) } -> std::same_as<LightSample<Real>>;
    { L::from_scene(scene) } -> std::same_as<std::vector<L>>;
    { L::count_in(scene) } -> std::convertible_to<std::size_t>;
};

}  // namespace prism
