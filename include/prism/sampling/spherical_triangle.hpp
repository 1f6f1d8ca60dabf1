// A triangle sampled by the solid angle it subtends: Arvo, "Stratified Sampling of Spherical
// Triangles" (SIGGRAPH 1995), the method pbrt-v4 uses for its triangle lights (Pharr, Jakob and
// Humphreys, 4th ed., sec. 6.5.4).
//
// Sampled by area, a triangle light's estimate carries |x - q|^2 / |cos theta_q|: unbounded for
// shading points next to the light (a ceiling beside a hanging light box), whose rare samples on
// the nearest part of the triangle are fireflies that no stratification removes. Sampled
// uniformly in the solid angle Omega it subtends, the estimate is L f cos theta_x Omega: bounded,
// and smooth in the sample, so a stratified or low-discrepancy sampler reduces its error as it
// reduces a smooth integrand's.
//
// Arvo's construction: u.x picks the sub-triangle A B C' of area u.x Omega, which fixes C' on
// the arc A C (the spherical law of cosines solved for the cosine of arc A C'); u.y then picks
// the direction on the arc B C' whose cosine with B is uniform, which is uniform in area within
// the sub-triangle's slice. The map is continuous and measure-preserving up to the factor Omega,
// so strata of the unit square stay strata of the spherical triangle.
//
// It computes in double whatever the renderer's precision: in float, its cosines near 1 bent
// the distribution measurably (a quarter of a triangle of 0.005 sr received 0.2526 of 2 million
// samples for its 0.2544 of the solid angle, 6 standard deviations); in double it received 0.2548.
#pragma once

#include <prism/math/floating_point.hpp>
#include <prism/math/vector.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace prism {

class SphericalTriangle {
    using Real = double;

public:
    // Below this solid angle (steradians) callers sample a triangle by area instead: the area
    // density varies little over a triangle seen that small, and sampling it by solid angle
    // left the same error on the hw7 Cornell boxes (within 0.5% at 16 and 64 samples a pixel)
    // for 4-14% more render time than from 0.05 sr on (bench/RESULTS.md, "Object lights").
    // Near 2 pi the viewpoint lies in the triangle's plane, inside it, where the angles
    // degenerate (pbrt-v4 draws that line too).
    static constexpr double smallest_solid_angle = 0.05, largest_solid_angle = 6.22;

    // The triangle with vertex `v0` and edges `edge1`, `edge2` (as LightMesh keeps it), seen
    // from `viewpoint`.
    template <Scalar Input>
    SphericalTriangle(const Vec3<Input>& viewpoint, const Vec3<Input>& v0, const Vec3<Input>& edge1,
                      const Vec3<Input>& edge2)
        : SphericalTriangle(Vec3<Real>(v0) - Vec3<Real>(viewpoint), Vec3<Real>(edge1), Vec3<Real>(edge2)) {}

    // The squared distance from `centre` (any point near the triangle: LightMesh gives its
    // centroid) beyond which the triangle with vertex `v0` and edges `edge1`, `edge2` is
    // certainly not samplable(): from a viewpoint p with |p - centre| > R + sqrt(A / Omega_min)
    // (R the farthest vertex from the centre, A the area), every point of the triangle is at
    // least d = |p - centre| - R away, and the solid angle, the integral of cos / r^2 over the
    // triangle, is at most A / d^2 < Omega_min. Callers compare |p - centre|^2, computed in
    // their own precision, and skip the constructor's three square roots in double: the
    // answer is the one samplable() would give, since the bound is taken for 0.999 Omega_min
    // (far beyond the rounding of samplable()'s own double arithmetic) and widened by 1e-4
    // (far beyond the rounding of a float squared distance). Infinite where that is not
    // representable: such a triangle is never skipped.
    template <Scalar Input>
    static Input unsamplable_beyond(const Vec3<Input>& v0, const Vec3<Input>& edge1, const Vec3<Input>& edge2,
                                    const Vec3<Input>& centre) {
        const Vec3<Real> a(v0), b = a + Vec3<Real>(edge1), c = a + Vec3<Real>(edge2), m(centre);
        const Real reach = std::sqrt(std::max({glm::dot(a - m, a - m), glm::dot(b - m, b - m), glm::dot(c - m, c - m)}));
        const Real area = glm::length(glm::cross(Vec3<Real>(edge1), Vec3<Real>(edge2))) / 2;
        const Real far = reach + std::sqrt(area / (0.999 * smallest_solid_angle));
        const Real bound = far * far * (1 + 1e-4);
        if (!(bound < Real(std::numeric_limits<Input>::max()))) return std::numeric_limits<Input>::infinity();
        return next_up(Input(bound));
    }

    // The solid angle the triangle subtends, in steradians (0 for a degenerate view).
    Real solid_angle() const { return small_ ? angle(determinant_, denominator_) : solid_angle_; }
    // Whether callers sample the triangle by its solid angle (see smallest_solid_angle).
    bool samplable() const { return solid_angle_ >= smallest_solid_angle && solid_angle_ <= largest_solid_angle; }

    // A unit direction towards the triangle, uniform in solid angle (density 1 / solid_angle()),
    // for u uniform in [0, 1)^2; for a view of positive area (solid_angle() in (0, 2 pi), as
    // samplable() ensures). Tested from 3e-4 to 5 sr.
    template <Scalar Output>
    Vec3<Output> sample(const Vec2<Output>& u) const {
        return Vec3<Output>(sample_direction(Real(u.x), Real(u.y)));
    }

private:
    // From the viewpoint, `ra` towards v0. Only the solid angle: callers that do not sample
    // (a triangle under smallest_solid_angle, or pdf()) need nothing else, and sample_direction
    // works out the rest.
    SphericalTriangle(const Vec3<Real>& ra, const Vec3<Real>& edge1, const Vec3<Real>& edge2)
        : ra_(ra), rb_(ra + edge1), rc_(ra + edge2) {
        la_ = glm::length(ra_), lb_ = glm::length(rb_), lc_ = glm::length(rc_);
        if (!(la_ > 0) || !(lb_ > 0) || !(lc_ > 0)) return;
        // The determinant det(ra, rb, rc) is ra . (edge1 x edge2): no difference of nearly
        // equal long vectors, so it keeps its relative precision for far, small triangles.
        determinant_ = glm::dot(ra, glm::cross(edge1, edge2));
        // Van Oosterom and Strackee (1983): tan(Omega / 2) = |det| / (la lb lc + (ra . rb) lc +
        // (ra . rc) lb + (rb . rc) la); atan2 keeps Omega above pi where the denominator is negative.
        denominator_ =
            la_ * lb_ * lc_ + glm::dot(ra_, rb_) * lc_ + glm::dot(ra_, rc_) * lb_ + glm::dot(rb_, rc_) * la_;
        // A view whose tangent is below smallest_solid_angle / 2 is smaller than that angle (atan x
        // < x): samplable() is false without the arctangent, which solid_angle() works out only
        // when asked. The comparison reads the values atan2 would, and its result would be below
        // the bound by a relative 2e-4 or more, far beyond its rounding, so the answer is the one
        // the angle gives. Most views of the hw7 Cornell boxes' light are that small; their
        // arctangent (in double) was 3-5% of those renders' time (perf), and without it hw7
        // path_glass and glossy_area_small take 0.98 of it (bench/paired.sh, 7 rounds).
        small_ = denominator_ > 0 && std::abs(determinant_) < Real(smallest_solid_angle / 2) * denominator_;
        // A view with two vertices in one direction (no interior angle at a) has a zero
        // determinant, so a solid angle of 0 or 2 pi: never samplable().
        if (!small_) solid_angle_ = angle(determinant_, denominator_);
    }

    static Real angle(Real determinant, Real denominator) { return 2 * std::atan2(std::abs(determinant), denominator); }

    Vec3<Real> sample_direction(Real u1, Real u2) const {
        const Vec3<Real> a = ra_ / la_, b = rb_ / lb_, c = rc_ / lc_;
        // The interior angle at a: between the great circles towards b and towards c, whose
        // planes' normals a x b and a x c meet at the same angle. Their cross product is
        // a det(a, b, c), which gives the sine without a square root of 1 - cos^2.
        const Vec3<Real> normal_ab = glm::cross(a, b), normal_ac = glm::cross(a, c);
        const Real lengths = glm::length(normal_ab) * glm::length(normal_ac);
        const Real cos_alpha = glm::dot(normal_ab, normal_ac) / lengths;
        const Real sin_alpha = std::abs(determinant_) / (la_ * lb_ * lc_ * lengths);
        // The sub-triangle a b c' of area u1 Omega. With s and t the sine and cosine of its
        // area less alpha, Arvo's closed form gives the cosine q of the arc a c'.
        const Real sub_area = u1 * solid_angle();
        const Real sin_sub = std::sin(sub_area), cos_sub = std::cos(sub_area);
        const Real s = sin_sub * cos_alpha - cos_sub * sin_alpha;
        const Real t = cos_sub * cos_alpha + sin_sub * sin_alpha;
        const Real cos_ab = glm::dot(a, b);
        const Real k1 = t - cos_alpha, k2 = s + sin_alpha * cos_ab;
        const Real denominator = (k2 * s + k1 * t) * sin_alpha;
        const Real q = denominator != 0 ? std::clamp(((k2 * t - k1 * s) * cos_alpha - k2) / denominator, Real(-1), Real(1))
                                        : Real(1);
        const Vec3<Real> c_prime = q * a + std::sqrt(std::max(Real(0), 1 - q * q)) * orthogonal_part(c, a);
        // Along the arc from b to c', the cosine with b is uniform.
        const Real z = 1 - u2 * (1 - glm::dot(c_prime, b));
        return z * b + std::sqrt(std::max(Real(0), 1 - z * z)) * orthogonal_part(c_prime, b);
    }

    // The unit direction of v's part orthogonal to the unit vector w (zero where v is along w).
    static Vec3<Real> orthogonal_part(const Vec3<Real>& v, const Vec3<Real>& w) {
        const Vec3<Real> part = v - glm::dot(v, w) * w;
        const Real length = glm::length(part);
        return length > 0 ? part / length : Vec3<Real>(0);
    }

    Vec3<Real> ra_, rb_, rc_;  // from the viewpoint to the vertices
    Real la_ = 0, lb_ = 0, lc_ = 0, determinant_ = 0, denominator_ = 0;
    Real solid_angle_ = 0;  // left 0 where small_, which samplable() then reads as too small
    bool small_ = false;    // certainly below smallest_solid_angle, solid_angle_ not worked out
};

}  // namespace prism
