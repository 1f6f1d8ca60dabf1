// The course's 3D checkerboard texture (CENG795 hw4): space is cut into cubes of side 1 / Scale,
// shifted by Offset, and coloured by the parity of the cube's integer coordinates
//   (floor((x + Offset) Scale) + floor((y + Offset) Scale) + floor((z + Offset) Scale)) mod 2,
// even: WhiteColor, odd: BlackColor. The course's pseudo-code truncates towards zero (an int
// cast), which doubles the cubes that straddle 0; its scenes add an Offset (79 in perlin_types)
// to keep coordinates positive, where floor and truncation agree. floor keeps every cube the
// same size when they do not.
#pragma once

#include <prism/math/vector.hpp>

#include <cmath>

namespace prism {

template <Scalar Real>
struct Checkerboard {
    Real scale = 1;
    Real offset = 0;
    Vec3<Real> black{0};
    Vec3<Real> white{1};

    bool is_black(const Vec3<Real>& p) const {
        const Vec3<Real> cell = glm::floor((p + offset) * scale);
        // fmod of a sum of integers held exactly in Real: no int overflow far from the origin.
        return std::abs(std::fmod(cell.x + cell.y + cell.z, Real(2))) == Real(1);
    }

    Vec3<Real> colour(const Vec3<Real>& p) const { return is_black(p) ? black : white; }
};

}  // namespace prism
