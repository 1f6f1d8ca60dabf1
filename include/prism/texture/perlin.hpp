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
        const Axis x = axis(p.x), y = axis(p.y), z = axis(p.z);
        return corner_sum(x, y, z, corner_gradients(x.cell, y.cell, z.cell));
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

    // fractal() at p and, for each axis a, at p with coordinate a replaced by moved[a]: the far
    // ends of a bump's forward differences, each bit for bit what fractal() gives at its point.
    // The four points share the other two axes' offsets and weights, and the corners' gradients
    // wherever a moved coordinate stays in p's cell, so the three differences cost about one
    // value more, not three (the bumps of hw4 perlin_types_bump).
    static std::array<Real, 4> fractal_and_moved(const Vec3<Real>& p, const Vec3<Real>& moved, int octaves) {
        std::array<Real, 4> sums{};
        Real amplitude = 1;
        Vec3<Real> q = p, m = moved;
        for (int o = 0; o < std::max(octaves, 1); ++o) {
            const Axis x = axis(q.x), y = axis(q.y), z = axis(q.z);
            const Axis moved_x = axis(m.x), moved_y = axis(m.y), moved_z = axis(m.z);
            const Gradients here = corner_gradients(x.cell, y.cell, z.cell);
            const auto at = [&](const Axis& a, const Axis& b, const Axis& c) {
                const bool same_cell = a.cell == x.cell && b.cell == y.cell && c.cell == z.cell;
                return corner_sum(a, b, c, same_cell ? here : corner_gradients(a.cell, b.cell, c.cell));
            };
            const std::array<Real, 4> values{corner_sum(x, y, z, here), at(moved_x, y, z), at(x, moved_y, z), at(x, y, moved_z)};
            for (std::size_t k = 0; k < 4; ++k) sums[k] += amplitude * values[k];
            amplitude *= Real(0.5);
            q *= Real(2);
            m *= Real(2);
        }
        return sums;
    }

private:
    // The course's falloff: 1 at the corner, 0 one cell away, with zero first and second
    // derivatives at both ends.
    static Real weight(Real t) {
        const Real a = std::abs(t);
        return 1 - a * a * a * (a * (a * 6 - 15) + 10);
    }

    // One coordinate of a point: its cell, and a corner's offset and weight along the axis,
    // f and w(f) for the corner below (index 0), f - 1 and w(f - 1) for the one above.
    struct Axis {
        int cell;
        Real offset[2], weight[2];
    };
    static Axis axis(Real coordinate) {
        const Real cell = std::floor(coordinate);
        const Real f = coordinate - cell;  // position in the cell, [0, 1)
        return {cell_number(cell), {f, f - 1}, {weight(f), weight(f - 1)}};
    }

    // A cell's number as an int. Past 2^30 (a far point, or a high octave: each doubles the
    // coordinate) the int could not hold it, and converting it was undefined behaviour, as were
    // infinity and NaN. phi reads a number n only through |n| % 16, and corner_gradients reads
    // n + 0 to n + 16 at most, so a number replaced by one of its sign and remainder, 32 to 47
    // from zero, gives every corner the gradient it had: the same bits wherever the int held it.
    static int cell_number(Real cell) {
        constexpr Real far = Real(1 << 30);
        if (std::abs(cell) < far) return int(cell);
        if (!std::isfinite(cell)) return 32;  // NaN or infinity: the noise is NaN (its offset is)
        const int rest = int(std::fmod(std::abs(cell), Real(16)));
        return cell > 0 ? 32 + rest : -(32 + rest);
    }

    // The gradient numbers of a cell's 8 corners (corner = di + 2 dj + 4 dk).
    using Gradients = std::array<std::uint8_t, 8>;
    static Gradients corner_gradients(int i, int j, int k) {
        const int hk[2] = {phi(k), phi(k + 1)};
        int hjk[2][2];  // phi(j + dj + phi(k + dk))
        for (int dj = 0; dj < 2; ++dj)
            for (int dk = 0; dk < 2; ++dk) hjk[dj][dk] = phi(j + dj + hk[dk]);
        Gradients numbers;
        for (int corner = 0; corner < 8; ++corner)
            numbers[std::size_t(corner)] = std::uint8_t(phi(i + (corner & 1) + hjk[(corner >> 1) & 1][(corner >> 2) & 1]));
        return numbers;
    }

    static Real corner_sum(const Axis& x, const Axis& y, const Axis& z, const Gradients& numbers) {
        Real sum = 0;
        for (int corner = 0; corner < 8; ++corner) {
            const int di = corner & 1, dj = (corner >> 1) & 1, dk = (corner >> 2) & 1;
            const auto& g = gradients[numbers[std::size_t(corner)]];
            sum += x.weight[di] * y.weight[dj] * z.weight[dk] *
                   (Real(g[0]) * x.offset[di] + Real(g[1]) * y.offset[dj] + Real(g[2]) * z.offset[dk]);
        }
        return sum;
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
