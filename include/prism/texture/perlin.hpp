// Perlin's improved gradient noise (Perlin 2002, "Improving Noise") in the course's form (CENG795
// hw4): the 16-gradient table (the 12 cube-edge directions, four repeated), a 16-entry
// permutation phi hashing a lattice point (i, j, k) to phi(i + phi(j + phi(k))), and
//   n(p) = sum over the 8 corners c of the cell of  w(p.x - c.x) w(p.y - c.y) w(p.z - c.z) g_c . (p - c)
// with w(t) = 1 - (6|t|^5 - 15|t|^4 + 10|t|^3), the 2002 quintic that makes the noise C2 across
// cells. Octaves add noise at doubled frequency and halved amplitude. The value is in [-1, 1];
// a NoiseConversion turns it into [0, 1].
//
// The permutation is a fixed table, not shuffled per run, so images are reproducible. Its 16
// entries make the noise repeat every 16 lattice cells, which the course accepts.
//
// The expected images cannot fix the permutation (each renderer shuffled its own), only the
// look: absval draws dark zero-crossing lines (cube_perlin left), linear a soft mottle.
#pragma once

#include <prism/math/vector.hpp>
#include <prism/scene/scene.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace prism {

template <Scalar Real>
class PerlinNoise {
public:
    static constexpr std::array<std::array<std::int8_t, 3>, 16> gradients{{
        {1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0},
        {1, 0, 1}, {-1, 0, 1}, {1, 0, -1}, {-1, 0, -1},
        {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1},
        {1, 1, 0}, {-1, 1, 0}, {0, -1, 1}, {0, -1, -1},
    }};
    static constexpr std::array<std::uint8_t, 16> permutation{9, 3, 14, 0, 11, 6, 1, 12, 5, 15, 8, 2, 13, 7, 10, 4};

    // One octave at p, in [-1, 1].
    static Real noise(const Vec3<Real>& p) {
        const Vec3<Real> cell = glm::floor(p);
        const int i = int(cell.x), j = int(cell.y), k = int(cell.z);
        const Vec3<Real> f = p - cell;  // position in the cell, [0, 1)^3
        Real sum = 0;
        for (int corner = 0; corner < 8; ++corner) {
            const int di = corner & 1, dj = (corner >> 1) & 1, dk = (corner >> 2) & 1;
            const Vec3<Real> d = f - Vec3<Real>(Real(di), Real(dj), Real(dk));
            const auto& g = gradients[hash(i + di, j + dj, k + dk)];
            sum += weight(d.x) * weight(d.y) * weight(d.z) * (Real(g[0]) * d.x + Real(g[1]) * d.y + Real(g[2]) * d.z);
        }
        return sum;
    }

    // `octaves` octaves: sum over o of noise(2^o p) / 2^o. At least one.
    static Real fractal(const Vec3<Real>& p, int octaves) {
        Real sum = 0, amplitude = 1;
        Vec3<Real> q = p;
        for (int o = 0; o < std::max(octaves, 1); ++o) {
            sum += amplitude * noise(q);
            amplitude *= Real(0.5);
            q *= Real(2);
        }
        return sum;
    }

private:
    // The course's falloff: 1 at the corner, 0 one cell away, with zero first and second
    // derivatives at both ends.
    static Real weight(Real t) {
        const Real a = std::abs(t);
        return 1 - a * a * a * (a * (a * 6 - 15) + 10);
    }

    // n & 15 is n mod 16 for negative lattice coordinates too (two's complement), so cells left
    // of 0 get their own gradients instead of mirroring the ones on the right.
    static std::size_t hash(int i, int j, int k) {
        const auto phi = [](int n) { return int(permutation[std::size_t(n & 15)]); };
        return std::size_t(phi(i + phi(j + phi(k))));
    }
};

// The course's conversions of a noise value to [0, 1]: |n| ("patch": dark veins where the noise
// crosses zero) or (n + 1) / 2 ("vein" in the 2019 schema, a soft mottle).
template <Scalar Real>
inline Real convert_noise(Real n, scene::NoiseConversion conversion) {
    return conversion == scene::NoiseConversion::absval ? std::abs(n) : (n + 1) / 2;
}

}  // namespace prism
