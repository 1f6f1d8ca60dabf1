// Perlin's improved gradient noise (Perlin 2002, "Improving Noise") in the course's form (CENG795
// hw4): the 16-gradient table (the 12 cube-edge directions, four repeated), a 16-entry
// permutation P hashing a lattice point (i, j, k) to phi(i + phi(j + phi(k))) with
// phi(n) = P[|n| mod 16], and
//   n(p) = sum over the 8 corners c of the cell of  w(p.x - c.x) w(p.y - c.y) w(p.z - c.z) g_c . (p - c)
// with w(t) = 1 - (6|t|^5 - 15|t|^4 + 10|t|^3), the 2002 quintic that makes the noise C2 across
// cells. Octaves add noise at doubled frequency and halved amplitude. The value is in [-1, 1];
// a NoiseConversion turns it into [0, 1].
//
// The permutation and the |n| are the course's, recovered from its expected images (no public
// table has them): sphere_perlin's right sphere (NoiseScale 1, linear conversion, no specular
// highlight on most of it) gives the noise at 78,000 pixels as (pixel / diffuse irradiance) * 2
// - 1. Solving for a free gradient vector at each of the 1,692 lattice points behind them (least
// squares, the weight form above) leaves an rms residual of 0.004, so the formula and the
// world-space position are right; every well-determined vector is one of the 12 edge directions.
// The gradients repeat every 16 cells along x and y (33 and 32 pairs, no exception); along x,
// 121 rows of lattice points are cyclic shifts of one 16-long sequence g = G[P[m]] (no
// conflict), and the shifts, columns of P[(j + P[k]) mod 16], fix P uniquely (the only one of the
// 256 candidates consistent with all 121 rows). The left sphere lies at x < 0: phi(n) = P[|n| mod
// 16] renders it at 63.8 dB, P[n mod 16] (two's complement) at 17.7 dB.
#pragma once

#include <prism/math/vector.hpp>
#include <prism/scene/scene.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>

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
    static constexpr std::array<std::uint8_t, 16> permutation{4, 10, 11, 15, 14, 5, 13, 1, 6, 9, 3, 7, 8, 2, 0, 12};

    // One octave at p, in [-1, 1]. The sum over the corners in their order, each term's
    // products in the formula's order; but a corner's offset along an axis is one of two, f or
    // f - 1, and so is its weight, and the hash's inner steps are shared by the corners that
    // share (j, k) or k: 6 weights and 14 table steps where corner by corner took 24 and 24
    // (half the time a value, on hw4 perlin_types_bump a quarter of the render in its bumps).
    static Real noise(const Vec3<Real>& p) {
        const Vec3<Real> cell = glm::floor(p);
        const int i = int(cell.x), j = int(cell.y), k = int(cell.z);
        const Vec3<Real> f = p - cell;  // position in the cell, [0, 1)^3
        const Real dx[2] = {f.x, f.x - 1}, dy[2] = {f.y, f.y - 1}, dz[2] = {f.z, f.z - 1};
        const Real wx[2] = {weight(dx[0]), weight(dx[1])}, wy[2] = {weight(dy[0]), weight(dy[1])},
                   wz[2] = {weight(dz[0]), weight(dz[1])};
        const int hk[2] = {phi(k), phi(k + 1)};
        int hjk[2][2];  // phi(j + dj + phi(k + dk))
        for (int dj = 0; dj < 2; ++dj)
            for (int dk = 0; dk < 2; ++dk) hjk[dj][dk] = phi(j + dj + hk[dk]);
        Real sum = 0;
        for (int corner = 0; corner < 8; ++corner) {
            const int di = corner & 1, dj = (corner >> 1) & 1, dk = (corner >> 2) & 1;
            const auto& g = gradients[std::size_t(phi(i + di + hjk[dj][dk]))];
            sum += wx[di] * wy[dj] * wz[dk] * (Real(g[0]) * dx[di] + Real(g[1]) * dy[dj] + Real(g[2]) * dz[dk]);
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

    // phi(n) = P[|n| mod 16], as the course hashes: the noise at negative coordinates mirrors
    // the lattice's gradients (see the header). A corner's gradient is G[phi(i + phi(j + phi(k)))].
    static int phi(int n) { return int(permutation[std::size_t(std::abs(n) % 16)]); }
};

// The course's conversions of a noise value to [0, 1]: |n| ("patch": dark veins where the noise
// crosses zero) or (n + 1) / 2 ("vein" in the 2019 schema, a soft mottle).
template <Scalar Real>
inline Real convert_noise(Real n, scene::NoiseConversion conversion) {
    return conversion == scene::NoiseConversion::absval ? std::abs(n) : (n + 1) / 2;
}

}  // namespace prism
