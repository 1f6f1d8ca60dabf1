// Floating-point error helpers for float and double alike: the unit roundoff, pbrt's gamma(n)
// bound on n successive roundings, and stepping to the neighbouring representable value.
// Each overload set is written once as a template so a double build can never silently pick a
// float-sized bound (the pbrt-v4 NextFloatUp(double) lesson).
#pragma once

#include <prism/math/vector.hpp>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

namespace prism {

// Half of machine epsilon: the largest relative error of one correctly rounded operation.
template <Scalar Real>
constexpr Real unit_roundoff = std::numeric_limits<Real>::epsilon() * Real(0.5);

// gamma(n) = n u / (1 - n u) bounds the relative error of n successive rounded operations
// (Higham; pbrt-v4 section 6.8).
template <Scalar Real>
constexpr Real gamma(int n) {
    return (Real(n) * unit_roundoff<Real>) / (Real(1) - Real(n) * unit_roundoff<Real>);
}

// The next representable value above v, as std::nextafter(v, +inf) gives it. GCC does not
// inline nextafter: every call goes into libm, and spawning rays from instanced surfaces (a
// dozen steps per ray, surface_error.hpp) spent a fifth of hw2 metal_glass_plates' render
// there. Finite IEEE values of one sign are ordered as their bit patterns, so one step of the
// pattern away from zero (or towards it, below zero) is one step up.
template <Scalar Real>
inline Real next_up(Real v) {
    using Bits = std::conditional_t<sizeof(Real) == sizeof(std::uint32_t), std::uint32_t, std::uint64_t>;
    if (!(v < std::numeric_limits<Real>::infinity())) return v;  // +inf and NaN stay
    if (v == 0) return std::numeric_limits<Real>::denorm_min();  // from +0 and -0 alike
    const Bits bits = std::bit_cast<Bits>(v);
    return std::bit_cast<Real>(v > 0 ? bits + 1 : bits - 1);
}

template <Scalar Real>
inline Real next_down(Real v) {
    return -next_up(-v);
}

}  // namespace prism
