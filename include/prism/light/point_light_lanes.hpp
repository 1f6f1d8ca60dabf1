// A point light sampled at a row of shading points at once, with the shadow ray from each point
// toward it: the light's samples for many points behind the light's own header, so that the
// integrators stay scalar and the SIMD stays in the lights' and the geometry's layers.
#pragma once

#include <prism/geometry/ray.hpp>
#include <prism/light/point_light.hpp>
#include <prism/memory/unconstructed.hpp>
#include <prism/simd/pack.hpp>

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <optional>

namespace prism {

// The shading points of a row, SoA: bit i of `shading` for point i.
template <Scalar Real, std::size_t Width>
struct ShadingRow {
    alignas(64) Real position[3][Width];
    alignas(64) Real normal[3][Width];
    Real time[Width];
    std::uint32_t shading = 0;
};

// One point light's samples and shadow rays for a row's points, made as the ray tracer makes
// them point by point (PointLight::sample, then its shadow ray, render/whitted_integrator.hpp), with each lane
// computing the scalar code's operations in its order: the same directions, radiances,
// cosines and rays, bit for bit. The lit lanes are those the scalar `cos <= 0` test lets
// through (NaN included); returns them, whose rays are made. The square roots and
// divisions of eight points (four in double) then share vector instructions (hw2 mirror_room: 0.88 of
// the wall time with the rays made point by point).
// `epsilon`: where rays leave by the scene's epsilon, the origins are made here, lane by lane as
// leaving_ray makes them (the point moved by epsilon along the normal, to the side the ray
// leaves by); without, `origin_of(i, direction)` gives point i's origin (its error-bounded
// one), called lane by lane in the lit lanes' order.
template <std::size_t RowWidth, Scalar Real, class OriginOf>
std::uint32_t point_light_lanes(const PointLight<Real>& light, const ShadingRow<Real, RowWidth>& row,
                                const std::optional<Real>& epsilon, std::array<Vec3<Real>, RowWidth>& directions,
                                std::array<Vec3<Real>, RowWidth>& radiances, std::array<Real, RowWidth>& cosines,
                                Unconstructed<Ray<Real>, RowWidth>& shadows, OriginOf origin_of) {
    // One 32-byte register's lanes at a time (8 floats, 4 doubles), as LightMesh::view_weights
    // takes them: in 64-byte lanes (16 floats) hw4 perlin_types_nobump, glass_plates_point and
    // hw2 mirror_room took 1.08, 1.06 and 1.06 times as long on the Intel VM, the same images.
    // Why is not settled: neither two 256-bit divisions for each 512-bit one nor the
    // double-refine packets in 256-bit halves changed anything elsewhere (bench/RESULTS.md,
    // "Whole renders").
    constexpr int width = int(32 / sizeof(Real));
    static_assert(int(RowWidth) % width == 0);
    using Lanes = simd::Pack<Real, width>;
    std::uint32_t lit = 0;
    for (int first = 0; first < int(RowWidth); first += width) {
        const std::uint32_t shading = (row.shading >> first) & ((std::uint32_t(1) << width) - 1);
        if (shading == 0) continue;
        Lanes p[3], n[3], to_light[3];
        for (int axis = 0; axis < 3; ++axis) {
            p[axis] = Lanes::load(row.position[axis] + first);
            n[axis] = Lanes::load(row.normal[axis] + first);
            to_light[axis] = Lanes::broadcast(light.position[axis]) - p[axis];
        }
        // PointLight::sample: glm's dot sums (x + y) + z.
        const Lanes distance_squared = (to_light[0] * to_light[0] + to_light[1] * to_light[1]) + to_light[2] * to_light[2];
        const Lanes distance = simd::sqrt(distance_squared);
        Lanes direction[3], radiance[3];
        for (int axis = 0; axis < 3; ++axis) {
            direction[axis] = to_light[axis] / distance;
            radiance[axis] = Lanes::broadcast(light.intensity[axis]) / distance_squared;
        }
        const Lanes cosine = (n[0] * direction[0] + n[1] * direction[1]) + n[2] * direction[2];
        const std::uint32_t lanes_lit = shading & (!(cosine <= Lanes::broadcast(Real(0)))).bits();
        // Rows 0-2 the directions, 3-5 the radiances, 6-8 the origins, 9-11 the shadow rays'
        // directions, 12 the cosines.
        alignas(64) Real stored[13][width];
        for (int axis = 0; axis < 3; ++axis) direction[axis].store(stored[axis]);
        Lanes origin[3], aim[3];
        if (epsilon) {
            // leaving_ray: the origin on the side dot(direction, normal) >= 0 names (the same
            // products as the cosine's, so the same sum).
            const auto towards = cosine >= Lanes::broadcast(Real(0));
            const Lanes offset = Lanes::broadcast(*epsilon);
            for (int axis = 0; axis < 3; ++axis) origin[axis] = p[axis] + select(towards, n[axis], -n[axis]) * offset;
        } else {
            alignas(64) Real origins[3][width] = {};
            for (std::uint32_t rest = lanes_lit; rest != 0; rest &= rest - 1) {
                const int lane = std::countr_zero(rest);
                const Vec3<Real> made =
                    origin_of(std::size_t(first + lane), Vec3<Real>(stored[0][lane], stored[1][lane], stored[2][lane]));
                for (int axis = 0; axis < 3; ++axis) origins[axis][lane] = made[axis];
            }
            for (int axis = 0; axis < 3; ++axis) origin[axis] = Lanes::load(origins[axis]);
        }
        for (int axis = 0; axis < 3; ++axis) aim[axis] = (p[axis] + direction[axis] * distance) - origin[axis];
        // unit_vector: v * (1 / sqrt(dot(v, v))); a light at infinity keeps the sample's direction.
        const Lanes inverse_length =
            Lanes::broadcast(Real(1)) / simd::sqrt((aim[0] * aim[0] + aim[1] * aim[1]) + aim[2] * aim[2]);
        const auto finite = distance != Lanes::broadcast(infinity<Real>);
        for (int axis = 0; axis < 3; ++axis) {
            radiance[axis].store(stored[3 + axis]);
            origin[axis].store(stored[6 + axis]);
            select(finite, aim[axis] * inverse_length, direction[axis]).store(stored[9 + axis]);
        }
        cosine.store(stored[12]);
        alignas(64) Real distances[width];
        distance.store(distances);
        for (std::uint32_t rest = shading; rest != 0; rest &= rest - 1) {
            const int lane = std::countr_zero(rest);
            const std::size_t i = std::size_t(first + lane);
            directions[i] = Vec3<Real>(stored[0][lane], stored[1][lane], stored[2][lane]);
            radiances[i] = Vec3<Real>(stored[3][lane], stored[4][lane], stored[5][lane]);
            cosines[i] = stored[12][lane];
            if (!((lanes_lit >> lane) & 1)) continue;
            Ray<Real>& made = shadows.make(i);
            made.origin = Vec3<Real>(stored[6][lane], stored[7][lane], stored[8][lane]);
            made.direction = Vec3<Real>(stored[9][lane], stored[10][lane], stored[11][lane]);
            made.t_min = Real(0);
            made.t_max = distances[lane];
            made.time = row.time[i];
        }
        lit |= lanes_lit << first;
    }
    return lit;
}

}  // namespace prism
