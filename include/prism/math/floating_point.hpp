// Floating-point error helpers for float and double alike: the unit roundoff, pbrt's gamma(n)
// bound on n successive roundings, and stepping to the neighbouring representable value.
// Each overload set is written once as a template so a double build can never silently pick a
// float-sized bound (the pbrt-v4 NextFloatUp(double) lesson).
#pragma once

#include <prism/math/vector.hpp>

#include <cmath>
#include <limits>

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

template <Scalar Real>
inline Real next_up(Real v) {
    return std::nextafter(v, std::numeric_limits<Real>::infinity());
}

template <Scalar Real>
inline Real next_down(Real v) {
    return std::nextafter(v, -std::numeric_limits<Real>::infinity());
}

}  // namespace prism
