// Möller-Trumbore ray-triangle intersection with the fixed absolute epsilons students use
// (reject when |n|^2 < 1e-12 or |n.d| < 1e-8). Kept as the baseline the accuracy charts beat:
// on dense meshes of tiny triangles these thresholds throw valid hits away.
#pragma once

#include <prism/geometry/triangle_hit.hpp>

#include <cmath>

namespace prism {

struct NaiveEpsilon {
    template <Scalar Real> using Storage = Real;

    template <Scalar Real>
    struct Prepared {
        Vec3<Real> origin;
        Vec3<Real> direction;
        explicit Prepared(const Ray<Real>& ray) : origin(ray.origin), direction(ray.direction) {}
    };

    template <Scalar Real>
    static bool intersect(const Prepared<Real>& ray, const Vec3<Real>& p0, const Vec3<Real>& p1,
                          const Vec3<Real>& p2, Real t_min, Real t_max, TriangleHit<Real>& hit) {
        const Vec3<Real> e1 = p1 - p0;
        const Vec3<Real> e2 = p2 - p0;
        const Vec3<Real> normal = glm::cross(e1, e2);
        if (glm::dot(normal, normal) < Real(1e-12)) return false;  // "degenerate"
        if (std::abs(glm::dot(normal, ray.direction)) < Real(1e-8)) return false;  // "parallel"
        const Vec3<Real> pvec = glm::cross(ray.direction, e2);
        const Real det = glm::dot(e1, pvec);
        const Real inverse_det = Real(1) / det;
        const Vec3<Real> tvec = ray.origin - p0;
        const Real b1 = glm::dot(tvec, pvec) * inverse_det;
        if (b1 < 0 || b1 > 1) return false;
        const Vec3<Real> qvec = glm::cross(tvec, e1);
        const Real b2 = glm::dot(ray.direction, qvec) * inverse_det;
        if (b2 < 0 || b1 + b2 > 1) return false;
        const Real t = glm::dot(e2, qvec) * inverse_det;
        if (!(t > t_min && t <= t_max)) return false;
        hit.t = t;
        hit.b1 = b1;
        hit.b2 = b2;
        return true;
    }
};

}  // namespace prism
