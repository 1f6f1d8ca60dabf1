// Leaving a surface without an epsilon: a hit point carried with a bound on its floating-point
// error, and the ray origin pushed just past that bound along the normal (pbrt-v4, Pharr, Jakob
// and Humphreys, "Physically Based Rendering" 4th ed., section 6.8: the triangle and sphere
// bounds of 6.8.5, the transform bound of 6.8.6, OffsetRayOrigin of 6.8.6 "Robust spawned rays"),
// plus the margins pbrt handles elsewhere: the intersector's own error when a leaving ray meets
// its triangle again, and the world/object round trip of instanced rays.
// Every bound is a template on Real and uses gamma<Real>, so a double build gets double-sized
// bounds (pbrt-v4's double build silently used float-sized ones).
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/math/floating_point.hpp>
#include <prism/math/transform.hpp>
#include <prism/simd/pack.hpp>

#include <algorithm>
#include <array>
#include <cmath>

namespace prism {

// A point and a per-axis bound on the distance of the computed point from the exact one.
template <Scalar Real>
struct PointWithError {
    Vec3<Real> point{0};
    Vec3<Real> error{0};
};

// The hit point of a triangle from its barycentrics rather than from ray.at(t): the exact
// b0 p0 + b1 p1 + b2 p2 lies in the triangle's plane whatever the barycentrics' own error, so
// only the rounding of this sum moves the point off the plane, and gamma(7) bounds it
// (pbrt-v4 6.8.5). ray.at(t) would carry the error of t times the whole ray length.
// b0 is taken as 1 - b1 - b2, as TriangleHit reports two weights: if the three do not sum to
// exactly 1, the point moves by (sum - 1) p_i, whose component along the normal is
// (sum - 1) (n . p_hit), within a few u of sum |b_i p_i|; gamma(7) covers it.
template <Scalar Real>
PRISM_FORCE_INLINE inline PointWithError<Real> triangle_hit_point(const Vec3<Real>& p0, const Vec3<Real>& p1,
                                                                      const Vec3<Real>& p2, Real b1, Real b2) {
    const Real b0 = Real(1) - b1 - b2;
    const Vec3<Real> w0 = b0 * p0, w1 = b1 * p1, w2 = b2 * p2;
    return {w0 + w1 + w2, gamma<Real>(7) * (abs_each(w0) + abs_each(w1) + abs_each(w2))};
}

// The same for vertices stored wider than the traversal precision (DoubleRefine keeps them in
// double under float rays): the point is interpolated in double, then rounded once to Real.
// That rounding moves it by at most u |point| per axis; gamma(2) rather than gamma(1) leaves
// room for the rounding of the bound's own arithmetic, next_up for the double bound's rounding.
template <Scalar Real>
    requires(!std::same_as<Real, double>)
PointWithError<Real> triangle_hit_point(const Vec3<double>& p0, const Vec3<double>& p1, const Vec3<double>& p2,
                                        Real b1, Real b2) {
    const PointWithError<double> wide = triangle_hit_point(p0, p1, p2, double(b1), double(b2));
    const Vec3<Real> point(wide.point);
    Vec3<Real> error = gamma<Real>(2) * abs_each(point);
    for (int axis = 0; axis < 3; ++axis) error[axis] += next_up(Real(wide.error[axis]));
    return {point, error};
}

// The point a ray leaving a triangle starts from: triangle_hit_point, with the bound widened
// along the normal by the margin the intersector itself needs. The new ray is tested against the
// same triangle again, and the watertight test has errors of its own: it computes t det as
// sum e_i z_i from edge functions e_i (2D cross products of sheared vertex coordinates that are
// each a few u R off, R the distance from the hit point to the farthest vertex) and vertex depths
// z_i <= R, so its error is some tens of u R^3, while its exact value for an origin at height h
// above the plane is 2 A h (A the triangle's area). Past h ~ c u R (R^2 / 2A), the computed t
// keeps the sign of the exact one and the triangle cannot be found again. This matters where a
// triangle is large next to its distance from the origin (a ground quad around the origin, where
// pbrt's sum |b_i p_i| is small next to R) and grows for slivers (R^2 / 2A large); elsewhere it is
// far below the hit point's own error. pbrt-v4 instead rejects, in the intersector, every hit
// with t below that error (Triangle::Intersect's deltaT); added to Watertight, that bound drops
// valid hits: a 1e-7 triangle at distance 1 in float, a leak-test ray, 6% of the Reintersect
// protocol's incoming rays. c = 16: in that protocol c = 4 already leaves no re-hit over 9
// seeds; the estimate above gives ~18. The margin is taken in the precision the triangle is
// tested in (Vertex: double for DoubleRefine). Forced inline: out of line, the call and its
// vectors passed through memory cost hw1 simple_shading 2% of its instructions (GCC inlines it
// or not as the shading code around it grows).
template <Scalar Real, Scalar Vertex>
PRISM_FORCE_INLINE inline PointWithError<Real> triangle_spawn_point(const Vec3<Vertex>& p0, const Vec3<Vertex>& p1,
                                                                        const Vec3<Vertex>& p2, Real b1, Real b2) {
    PointWithError<Real> result = triangle_hit_point(p0, p1, p2, b1, b2);
    // In double for both precisions: R^3 overflows float for coordinates past ~1e12.
    const glm::dvec3 q0(p0), q1(p1), q2(p2), hit(result.point);
    const double reach_squared = std::max({glm::dot(q0 - hit, q0 - hit), glm::dot(q1 - hit, q1 - hit),
                                           glm::dot(q2 - hit, q2 - hit)});
    const glm::dvec3 cross = glm::cross(q1 - q0, q2 - q0);
    // (2A)^2: zero where glm::length(cross) would be, including underflow.
    const double twice_area_squared = glm::dot(cross, cross);
    // A triangle of no area has no plane to leave, and the watertight test never hits it.
    if (!(twice_area_squared > 0)) return result;
    // margin = c u R (R^2 / 2A), added along the unit normal n = cross / 2A: margin |n_i| is
    // c u R R^2 |cross_i| / (2A)^2, one square root and one division (a fifth of the function's
    // time went to the length's square root and four divisions).
    const double scale = double(gamma<Vertex>(16)) * std::sqrt(reach_squared) * (reach_squared / twice_area_squared);
    // Adding margin |n| to the box adds exactly margin to offset_ray_origin's |n| . error.
    for (int axis = 0; axis < 3; ++axis) result.error[axis] += next_up(Real(scale * std::abs(cross[axis])));
    return result;
}

// A sphere's hit point reprojected onto the sphere: q = p - center scaled by radius / |q|
// (pbrt-v4 6.8.5). The reprojected q is within gamma(5) |q| of the exact sphere whatever the
// error of p was; adding the center back is one more rounding, u |point| per axis, which
// gamma(2) |point| covers with room for the bound's own arithmetic. With center 0 this is
// pbrt's gamma(5) |p| exactly.
template <Scalar Real>
PointWithError<Real> sphere_hit_point(const Vec3<Real>& center, Real radius, const Vec3<Real>& approximate_point) {
    Vec3<Real> local = approximate_point - center;
    local *= radius / glm::length(local);
    const Vec3<Real> point = center + local;
    Vec3<Real> error = gamma<Real>(5) * abs_each(local);
    if (center != Vec3<Real>(0)) error += gamma<Real>(2) * abs_each(point);
    return {point, error};
}

// An affine transform applied to a point that carries an error (pbrt-v4 Transform::operator()
// on Point3fi): each coordinate is summed in pbrt's order, (m0 x + m1 y) + (m2 z + t), so that
// no term passes through more than three roundings and gamma(3) (|M| |p| + |t|) bounds the new
// rounding. The order is written out because GLM's is an implementation detail. The incoming
// error is carried through |M|, grown by (1 + gamma(3)) for the roundings it meets on the way.
// The matrix is taken as exact. For spawning rays from instances, see InstanceTransforms below:
// this bound alone does not cover the way back into object space.
template <Scalar Real>
PointWithError<Real> transform_point(const Mat4<Real>& matrix, const PointWithError<Real>& p) {
    PointWithError<Real> result;
    const Vec3<Real>& x = p.point;
    for (int row = 0; row < 3; ++row) {
        const Real m0 = matrix[0][row], m1 = matrix[1][row], m2 = matrix[2][row], t = matrix[3][row];
        result.point[row] = (m0 * x.x + m1 * x.y) + (m2 * x.z + t);
        result.error[row] =
            gamma<Real>(3) * (std::abs(m0 * x.x) + std::abs(m1 * x.y) + std::abs(m2 * x.z) + std::abs(t)) +
            (gamma<Real>(3) + Real(1)) *
                (std::abs(m0) * p.error.x + std::abs(m1) * p.error.y + std::abs(m2) * p.error.z);
    }
    return result;
}

// The origin of a ray leaving a surface toward `direction` (pbrt-v4 OffsetRayOrigin): moved
// along the unit `normal` by d = |n| . error, the largest extent of the error box along the
// normal, to the side the ray leaves by, so the exact surface lies behind the origin. The
// addition rounds, so each coordinate then steps one more representable value away.
// `normal` must be unit length (geometric, not shading: the plane the error is measured from).
// Forced inline: the instance's offset below calls it in its loop, and as a call (GCC's) every
// value live across it went to the stack and back: 195 instructions of the caller's own a ray
// on hw3 metal_plates_area (callgrind).
template <Scalar Real>
PRISM_FORCE_INLINE inline Vec3<Real> offset_ray_origin(const Vec3<Real>& point, const Vec3<Real>& error,
                                                       const Vec3<Real>& normal, const Vec3<Real>& direction) {
    const Real distance = glm::dot(abs_each(normal), error);
    Vec3<Real> offset = distance * normal;
    if (glm::dot(direction, normal) < 0) offset = -offset;
    Vec3<Real> origin = point + offset;
    for (int axis = 0; axis < 3; ++axis) {
        if (offset[axis] > 0) origin[axis] = next_up(origin[axis]);
        else if (offset[axis] < 0) origin[axis] = next_down(origin[axis]);
    }
    return origin;
}

template <Scalar Real>
Vec3<Real> offset_ray_origin(const PointWithError<Real>& point, const Vec3<Real>& normal,
                             const Vec3<Real>& direction) {
    return offset_ray_origin(point.point, point.error, normal, direction);
}

// Rays leaving an instanced surface. The traversal maps every world ray into object space with
// world_to_object, rounded once to Real from the inverse of the instance's transform; the
// integrator maps points out with object_to_world. A world-space bound (transform_point above,
// pbrt's way) misses three errors of that round trip: the two rounded matrices are not exact
// inverses (|A M - I| grows with the transform's condition number: a scale of 100 on one axis
// and 0.01 on another makes it ~1e4 u), the world origin is rounded, and the traversal's own
// A * origin rounds again. Measured on random instanced triangles (tests/test_self_intersection),
// those leave 0.2-0.6% of spawned rays re-hitting their triangle in float and double alike. So
// the origin is offset in object space, where the triangle is exact, by the hit's error plus a
// bound on the round trip, and only then mapped to world. Instances without a transform are
// traversed in world space and need only the plain offset_ray_origin above.
template <Scalar Real>
struct InstanceTransforms {
    Mat4<Real> object_to_world{1};  // M, rounded from the scene's transform
    Mat4<Real> world_to_object{1};  // A, rounded from its inverse: what the traversal applies
    Mat4<Real> residual{0};         // a bound on |A M - I|, entry by entry
    // The round trip's bound as one affine map of |o| (round_trip below), computed once here
    // rather than for every ray that leaves the instance.
    Mat3<Real> round_trip_linear{0};
    Vec3<Real> round_trip_constant{0};
    // The same four columns (K's three, then k) as rows of 4 lanes, the fourth lane 0: the
    // instance's offset below works a pass out in one register per quantity.
    std::array<std::array<Real, 4>, 4> round_trip_lanes{};

    // Rounds the matrices exactly as Placement does, so A is the traversal's own matrix.
    explicit InstanceTransforms(const glm::dmat4& transform)
        : object_to_world(transform), world_to_object(glm::inverse(transform)) {
        // The bound is derived from the double matrices, never by widening the rounded ones back
        // to double (GCC 12.2's SLP vectorizer can fold such a double->Real->double round trip
        // into a copy). Each stored entry is its double value times (1 + d), |d| <= u, so
        // |A M - A_d M_d| <= (2u + u^2) |A_d| |M_d| <= gamma(2) |A_d| |M_d|; A_d M_d - I itself is
        // summed in double, off by at most gamma<double>(5) (|A_d| |M_d| + 1).
        const glm::dmat4 inverse = glm::inverse(transform);
        const double stored_rounding = double(gamma<Real>(2));
        for (int column = 0; column < 4; ++column)
            for (int row = 0; row < 3; ++row) {
                double product = 0, magnitude = 0;
                for (int k = 0; k < 4; ++k) {
                    product += inverse[k][row] * transform[column][k];
                    magnitude += std::abs(inverse[k][row] * transform[column][k]);
                }
                const double bound = std::abs(product - (column == row ? 1.0 : 0.0)) +
                                     gamma<double>(5) * (magnitude + 1.0) + stored_rounding * magnitude;
                residual[column][row] = next_up(Real(bound));
            }
        // The round trip o -> w = M o (pbrt's order) -> the traversal's A w, for an object-space
        // point with |o| <= m per axis, moves it by at most, per row r,
        //   (A M - I) o                            <= R m + R_t          (the residual)
        //   A times the error of w, |w - M o|      <= |A| g3 (|M| m + |t_M|)
        //   A w's own rounding, any order          <= g4 (|A| |w| + |t_A|),
        //     with |w| <= (1 + g3) (|M| m + |t_M|)
        // (R, |A|, |M| the 3x3 parts, R_t and t the translation columns, gk = gamma<Real>(k)):
        // together K m + k with K = R + c |A| |M|, k = R_t + c |A| |t_M| + g4 |t_A|,
        // c = g3 + g4 (1 + g3). Every term is non-negative. K and k are summed here in double
        // from the stored Real entries (exact in double), a dozen roundings of 2^-53 each, which
        // the factor 1 + 2^-30 covers; rounding to Real and one step up keeps them above that.
        // The caller evaluates K m + k in Real: each of its four terms meets at most four
        // roundings, so the computed value is at least (1 - g4) times the exact one, and the
        // factor 1 + g8 (> 1 / (1 - g4)) is folded in here, so the computed value still bounds
        // the round trip.
        const double g3 = double(gamma<Real>(3)), g4 = double(gamma<Real>(4));
        const double c = g3 + g4 * (1 + g3);
        const double widen = (1 + double(gamma<Real>(8))) * (1 + 0x1p-30);
        const auto wide_abs = [](Real v) { return std::abs(double(v)); };
        for (int row = 0; row < 3; ++row) {
            for (int column = 0; column < 3; ++column) {
                double through = 0;  // (|A| |M|)[row][column]
                for (int k = 0; k < 3; ++k)
                    through += wide_abs(world_to_object[k][row]) * wide_abs(object_to_world[column][k]);
                round_trip_linear[column][row] =
                    next_up(Real((double(residual[column][row]) + c * through) * widen));
            }
            double carried = 0;  // (|A| |t_M|)[row]
            for (int k = 0; k < 3; ++k) carried += wide_abs(world_to_object[k][row]) * wide_abs(object_to_world[3][k]);
            round_trip_constant[row] = next_up(
                Real((double(residual[3][row]) + c * carried + g4 * wide_abs(world_to_object[3][row])) * widen));
        }
        for (int row = 0; row < 3; ++row) {
            for (int column = 0; column < 3; ++column) round_trip_lanes[column][row] = round_trip_linear[column][row];
            round_trip_lanes[3][row] = round_trip_constant[row];
        }
    }

    // A bound on |A (M o) - o| per axis, as computed in Real, for every o with |o| <= magnitude.
    Vec3<Real> round_trip(const Vec3<Real>& magnitude) const {
        Vec3<Real> bound;
        for (int row = 0; row < 3; ++row)
            bound[row] = round_trip_linear[0][row] * magnitude.x + round_trip_linear[1][row] * magnitude.y +
                         round_trip_linear[2][row] * magnitude.z + round_trip_constant[row];
        return bound;
    }
};

// The world-space origin of a ray leaving an instanced surface toward `world_direction`, given
// the hit point in object space with its error (triangle_spawn_point or sphere_hit_point on the
// object-space shape) and the unit object-space geometric normal.
//
// Each three-component quantity is one 4-lane Pack (the fourth lane unused): the direction's
// and the final point's transforms, the round-trip bound, the error box and the offset. Every
// lane is the scalar expression's own IEEE operations in its order (transform_direction's,
// transform_point's, round_trip's, the plain offset_ray_origin's), so the origin has the same
// bits as the scalar form; the dot product's sum and the one-value steps stay scalar. As
// scalars (GCC kept them so), the two passes of a ray leaving the plates of hw3-hw4 took 235
// instructions, 9% of metal_plates_area's (bench/RESULTS.md, "Whole renders").
template <Scalar Real>
Vec3<Real> offset_ray_origin(const InstanceTransforms<Real>& instance, const PointWithError<Real>& object_point,
                             const Vec3<Real>& object_normal, const Vec3<Real>& world_direction) {
    using Lanes = simd::Pack<Real, 4>;
    const auto spread = [](const Vec3<Real>& v) { return Lanes::generate([&](int i) { return i < 3 ? v[i] : Real(0); }); };
    const auto broadcast = [](Real value) { return Lanes::broadcast(value); };
    const auto column = [](const Mat4<Real>& matrix, int k) { return Lanes::load(&matrix[k][0]); };
    const auto bound_row = [&](int k) { return Lanes::load(instance.round_trip_lanes[std::size_t(k)].data()); };

    // The side the ray leaves by, from the object-space direction (transform_direction's sums).
    const Mat4<Real>& to_object = instance.world_to_object;
    Real lanes[4];
    (column(to_object, 0) * broadcast(world_direction.x) + column(to_object, 1) * broadcast(world_direction.y) +
     column(to_object, 2) * broadcast(world_direction.z))
        .store(lanes);
    const Real facing = lanes[0] * object_normal.x + lanes[1] * object_normal.y + lanes[2] * object_normal.z;
    // -(d n) and d (-n) round alike, so the sign goes on the normal once.
    const Lanes normal = spread(facing < 0 ? -object_normal : object_normal);
    const Lanes absolute_normal = spread(abs_each(object_normal));
    const Lanes point = spread(object_point.point);
    const Lanes error = spread(object_point.error);

    // `magnitude` bounds |o|, the object-space origin, which the round-trip bound grows with.
    // It starts at the hit point's box; if the offset carries the origin past it, it is widened
    // by twice that offset and the bound recomputed. The offset grows with |o| only by a factor
    // ~ |A M - I|, far below 1, so the second pass fits: the loop is a safeguard, not a search.
    const Vec3<Real> start = abs_each(object_point.point) + object_point.error;
    Vec3<Real> magnitude = start;
    Vec3<Real> object_origin = object_point.point;
    for (int pass = 0; pass < 4; ++pass) {
        // The plain offset_ray_origin with the error grown by round_trip(magnitude).
        const Lanes round_trip = ((bound_row(0) * broadcast(magnitude.x) + bound_row(1) * broadcast(magnitude.y)) +
                                  bound_row(2) * broadcast(magnitude.z)) +
                                 bound_row(3);
        (absolute_normal * (error + round_trip)).store(lanes);
        const Real distance = lanes[0] + lanes[1] + lanes[2];
        const Lanes offset = broadcast(distance) * normal;
        Real steps[4];
        offset.store(steps);
        (point + offset).store(lanes);
        for (int axis = 0; axis < 3; ++axis) {
            if (steps[axis] > 0) lanes[axis] = next_up(lanes[axis]);
            else if (steps[axis] < 0) lanes[axis] = next_down(lanes[axis]);
            object_origin[axis] = lanes[axis];
        }
        const Vec3<Real> reached = abs_each(object_origin);
        if (reached.x <= magnitude.x && reached.y <= magnitude.y && reached.z <= magnitude.z) break;
        magnitude = start + Real(2) * abs_each(object_origin - object_point.point);
    }
    // Out to world space in pbrt's order, which the round-trip bound's first step assumes
    // (transform_point's sums).
    const Mat4<Real>& to_world = instance.object_to_world;
    ((column(to_world, 0) * broadcast(object_origin.x) + column(to_world, 1) * broadcast(object_origin.y)) +
     (column(to_world, 2) * broadcast(object_origin.z) + column(to_world, 3)))
        .store(lanes);
    return {lanes[0], lanes[1], lanes[2]};
}

}  // namespace prism
