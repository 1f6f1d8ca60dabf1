// Ray-sphere intersection in the sphere's object space. The quadratic is solved in the stable
// form (Press et al., Numerical Recipes 5.6): q = -(b + sign(b) sqrt(disc)) / 2, roots q/a and
// c/q, which avoids the cancellation of -b + sqrt(disc) when the ray starts near the sphere.
#pragma once

#include <prism/geometry/aabb.hpp>

#include <algorithm>
#include <cmath>

namespace prism {

template <Scalar Real>
struct SphereShape {
    Vec3<Real> center{0};
    Real radius = 1;

    Aabb<Real> bounds() const { return {center - Vec3<Real>(radius), center + Vec3<Real>(radius)}; }

    // Nearest root in (t_min, t_max]; the direction need not be unit length.
    bool intersect(const Ray<Real>& ray, Real t_min, Real t_max, Real& t_hit) const {
        const Vec3<Real> oc = ray.origin - center;
        const Real a = glm::dot(ray.direction, ray.direction);
        const Real half_b = glm::dot(oc, ray.direction);
        const Real c = glm::dot(oc, oc) - radius * radius;
        // An origin outside the sphere (c > 0) on a ray leaving it (half_b >= 0) gives q <= 0
        // below, so both roots c/q and q/a are at most 0 in floating point too: no root past a
        // t_min of 0 or more. Half the rays that miss a sphere (shadow rays, reflections) end
        // here, before the division and the square root; the answer is the one the full
        // computation gives.
        if (half_b >= 0 && c > 0 && t_min >= 0) return false;
        // c computed as |oc|^2 - r^2 would cancel catastrophically for far-away origins; the
        // difference of squares on the perpendicular distance keeps the discriminant accurate
        // (Haines et al., Ray Tracing Gems ch. 7).
        const Vec3<Real> perpendicular = oc - (half_b / a) * ray.direction;
        const Real discriminant_over_a = radius * radius - glm::dot(perpendicular, perpendicular);
        if (discriminant_over_a < 0) return false;
        const Real root = std::sqrt(a * discriminant_over_a);
        const Real q = half_b >= 0 ? -(half_b + root) : -(half_b - root);
        Real t0 = c / q, t1 = q / a;
        if (q == 0) t0 = t1 = 0;
        if (t0 > t1) std::swap(t0, t1);
        if (t0 > t_min && t0 <= t_max) {
            t_hit = t0;
            return true;
        }
        if (t1 > t_min && t1 <= t_max) {
            t_hit = t1;
            return true;
        }
        return false;
    }

    // The course's spherical texture coordinates of a point on the sphere (object space):
    // u = (pi - atan2(z, x)) / 2 pi, v = acos(y / r) / pi, with the position's derivatives along
    // them (not unit), which orient normal and bump maps.
    void parametrise(const Vec3<Real>& point, Vec2<Real>& uv, Vec3<Real>& dpdu, Vec3<Real>& dpdv) const {
        const Vec3<Real> d = point - center;
        const Real theta = std::acos(std::clamp(d.y / radius, Real(-1), Real(1)));
        const Real phi = std::atan2(d.z, d.x);
        uv = {(pi<Real> - phi) / (2 * pi<Real>), theta / pi<Real>};
        dpdu = 2 * pi<Real> * Vec3<Real>(d.z, 0, -d.x);
        dpdv = pi<Real> * Vec3<Real>(d.y * std::cos(phi), -radius * std::sin(theta), d.y * std::sin(phi));
    }
};

}  // namespace prism
