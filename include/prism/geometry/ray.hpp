// A ray with its parametric interval. Directions are not required to be unit length: instanced
// shapes intersect the ray transformed into object space, where keeping the same t means hits
// from every space compare directly.
#pragma once

#include <prism/math/vector.hpp>

namespace prism {

template <Scalar Real>
struct Ray {
    Vec3<Real> origin{0};
    Vec3<Real> direction{0, 0, -1};
    Real t_min = 0;
    Real t_max = infinity<Real>;
    // The instant in the shutter interval [0, 1] the ray samples; moving objects (MotionBlur)
    // are intersected where they are at that instant.
    Real time = 0;

    Vec3<Real> at(Real t) const { return origin + t * direction; }
};

}  // namespace prism
