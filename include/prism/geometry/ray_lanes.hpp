// A batch's rays as SIMD lanes: each ray's origin, direction, t_min and t_max (its first eight
// values, in that order) as a pack each, a ray in each lane, the lanes past `count` repeating
// ray 0. The side-by-side leaf and sphere tests (TrianglePackets::RayLanes, DirectTopLevel's
// sphere lanes) start from these; simd::load_transposed says why they are not filled lane by lane.
#pragma once

#include <prism/geometry/ray.hpp>
#include <prism/simd/pack.hpp>

#include <cstddef>

namespace prism {

// fields[0-2] the origins, [3-5] the directions, [6] t_min, [7] t_max.
template <Scalar Real>
PRISM_SIMD_INLINE inline void rays_as_lanes(const Ray<Real>* rays, int count, simd::Pack<Real, 8>* fields) {
    static_assert(offsetof(Ray<Real>, direction) == 3 * sizeof(Real) && offsetof(Ray<Real>, t_min) == 6 * sizeof(Real) &&
                  offsetof(Ray<Real>, t_max) == 7 * sizeof(Real) && sizeof(Ray<Real>) >= 8 * sizeof(Real));
    const Real* rows[8];
    for (int lane = 0; lane < 8; ++lane) rows[lane] = reinterpret_cast<const Real*>(&rays[lane < count ? lane : 0]);
    simd::load_transposed(rows, fields);
}

}  // namespace prism
