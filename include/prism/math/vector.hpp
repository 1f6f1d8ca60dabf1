// Vector and matrix aliases on GLM, templated on the scalar type, and the concept that names the
// scalar types prism is built for. Explicit aliases rather than injected macros, so the reader of
// any header sees the types it works with.
#pragma once

#include <prism/math/force_inline.hpp>

#include <glm/glm.hpp>

#include <cmath>
#include <concepts>
#include <limits>

namespace prism {

template <class T>
concept Scalar = std::same_as<T, float> || std::same_as<T, double>;

template <class Real> using Vec2 = glm::vec<2, Real, glm::defaultp>;
template <class Real> using Vec3 = glm::vec<3, Real, glm::defaultp>;
template <class Real> using Vec4 = glm::vec<4, Real, glm::defaultp>;
template <class Real> using Mat3 = glm::mat<3, 3, Real, glm::defaultp>;
template <class Real> using Mat4 = glm::mat<4, 4, Real, glm::defaultp>;

template <Scalar Real>
constexpr Real infinity = std::numeric_limits<Real>::infinity();

template <Scalar Real>
constexpr Real pi = Real(3.14159265358979323846);

// The component of largest magnitude; the watertight test picks its projection axis with it.
template <Scalar Real>
inline int max_dimension(const Vec3<Real>& v) {
    return v.x > v.y ? (v.x > v.z ? 0 : 2) : (v.y > v.z ? 1 : 2);
}

// The unit vector along v: glm::normalize's own operations, v * (1 / sqrt(v . v)), so the same
// bits (with -ffp-contract=off), but always inline. GCC leaves glm::normalize out of line in the
// integrators, a call per camera ray, shadow ray and half vector: 4-6% of the samples of the
// course's sphere scenes (hw1 spheres.json, hw2 mirror_room.json) were the call alone.
template <Scalar Real>
PRISM_FORCE_INLINE inline Vec3<Real> unit_vector(const Vec3<Real>& v) {
    return v * (Real(1) / std::sqrt(glm::dot(v, v)));
}

// |v| component by component with std::abs, which clears the sign bit (one and-not for the
// vector). glm::abs computes v >= 0 ? v : -v, which GCC 12 leaves as a compare, a negation and a
// blend per component: 4% of hw1 simple_shading's instructions went to the error bounds' three
// glm::abs (surface_error.hpp). The two differ only in the sign of the zero they give for -0 (and
// of a NaN), which no bound that uses this can see: the bounds are sums of magnitudes that end
// up added to a positive margin.
template <Scalar Real>
PRISM_FORCE_INLINE inline Vec3<Real> abs_each(const Vec3<Real>& v) {
    return {std::abs(v.x), std::abs(v.y), std::abs(v.z)};
}

}  // namespace prism
