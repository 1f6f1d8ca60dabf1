// Directions around a unit axis: an orthonormal frame, uniform and cosine-weighted hemispheres
// (environment lights, diffuse BRDF sampling) and the power-cosine lobe cos^p that Phong-type
// BRDFs sample (material/brdf.hpp).
#pragma once

#include <prism/math/vector.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

namespace prism {

// Two unit vectors completing `normal` (unit) to a right-handed orthonormal frame, without
// branches on the normal's orientation (Duff, Burgess, Christensen, Hery, Kensler, Liani and
// Villemin, "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017).
template <Scalar Real>
std::pair<Vec3<Real>, Vec3<Real>> orthonormal_basis(const Vec3<Real>& normal) {
    const Real sign = std::copysign(Real(1), normal.z);
    const Real a = -1 / (sign + normal.z);
    const Real b = normal.x * normal.y * a;
    return {Vec3<Real>(1 + sign * normal.x * normal.x * a, sign * b, -sign * normal.x),
            Vec3<Real>(b, sign + normal.y * normal.y * a, -normal.y)};
}

// The direction with cosine `cos_theta` to `normal` and azimuth 2 pi u around it.
template <Scalar Real>
Vec3<Real> hemisphere_direction(const Vec3<Real>& normal, Real cos_theta, Real u) {
    const auto [tangent, bitangent] = orthonormal_basis(normal);
    const Real sin_theta = std::sqrt(std::max(Real(0), 1 - cos_theta * cos_theta));
    const Real phi = 2 * pi<Real> * u;
    return sin_theta * std::cos(phi) * tangent + sin_theta * std::sin(phi) * bitangent + cos_theta * normal;
}

// Uniform over the hemisphere around `normal`: cos(theta) = 1 - u.x in (0, 1], density 1 / (2 pi).
template <Scalar Real>
Vec3<Real> sample_uniform_hemisphere(const Vec3<Real>& normal, const Vec2<Real>& u) {
    return hemisphere_direction(normal, 1 - u.x, u.y);
}

// Cosine-weighted: sin^2(theta) = u.x, so cos(theta) = sqrt(1 - u.x) in (0, 1], density cos / pi.
template <Scalar Real>
Vec3<Real> sample_cosine_hemisphere(const Vec3<Real>& normal, const Vec2<Real>& u) {
    return hemisphere_direction(normal, std::sqrt(1 - u.x), u.y);
}

// The power-cosine lobe around `axis`: cos(theta) = u.x^(1 / (exponent + 1)), density
// (exponent + 1) / (2 pi) cos^exponent(theta) on the hemisphere around the axis (Lafortune and
// Willems, "Using the Modified Phong Reflectance Model for Physically Based Rendering", 1994).
template <Scalar Real>
Vec3<Real> sample_power_cosine(const Vec3<Real>& axis, Real exponent, const Vec2<Real>& u) {
    return hemisphere_direction(axis, std::pow(u.x, 1 / (exponent + 1)), u.y);
}

template <Scalar Real>
Real power_cosine_pdf(Real cos_theta, Real exponent) {
    if (cos_theta <= 0) return 0;
    return (exponent + 1) / (2 * pi<Real>) * std::pow(cos_theta, exponent);
}

}  // namespace prism
