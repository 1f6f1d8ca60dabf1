// Watertight ray-triangle intersection: Woop, Benthin and Wald, "Watertight Ray/Triangle
// Intersection", JCGT 2(1), 2013. The ray is sheared so it runs along +z; edge functions are
// then evaluated in 2D with a consistent sign convention, so a ray through a shared edge or
// vertex hits at least one of the triangles that meet there. No epsilon is involved.
#pragma once

#include <prism/geometry/triangle_hit.hpp>

#include <cmath>
#include <utility>

namespace prism {

struct Watertight {
    template <Scalar Real> using Storage = Real;

    template <Scalar Real>
    struct Prepared {
        Vec3<Real> origin;
        int kx, ky, kz;      // axes permuted so that kz is the largest component of the direction
        Real sx, sy, sz;     // shear constants

        explicit Prepared(const Ray<Real>& ray) : origin(ray.origin) {
            const Vec3<Real>& d = ray.direction;
            kz = max_dimension(abs_each(d));
            kx = kz == 2 ? 0 : kz + 1;
            ky = kx == 2 ? 0 : kx + 1;
            // Swapping keeps the winding, and so the sign of the edge functions, consistent.
            if (d[kz] < 0) std::swap(kx, ky);
            sx = d[kx] / d[kz];
            sy = d[ky] / d[kz];
            sz = Real(1) / d[kz];
        }
    };

    template <Scalar Real>
    static bool intersect(const Prepared<Real>& ray, const Vec3<Real>& p0, const Vec3<Real>& p1,
                          const Vec3<Real>& p2, Real t_min, Real t_max, TriangleHit<Real>& hit) {
        const Vec3<Real> a = p0 - ray.origin;
        const Vec3<Real> b = p1 - ray.origin;
        const Vec3<Real> c = p2 - ray.origin;
        const Real ax = a[ray.kx] - ray.sx * a[ray.kz];
        const Real ay = a[ray.ky] - ray.sy * a[ray.kz];
        const Real bx = b[ray.kx] - ray.sx * b[ray.kz];
        const Real by = b[ray.ky] - ray.sy * b[ray.kz];
        const Real cx = c[ray.kx] - ray.sx * c[ray.kz];
        const Real cy = c[ray.ky] - ray.sy * c[ray.kz];

        Real u = cx * by - cy * bx;
        Real v = ax * cy - ay * cx;
        Real w = bx * ay - by * ax;
        // The paper falls back to double when an edge function is exactly zero, so that rays
        // through edges are decided consistently; in double itself there is nothing wider.
        if constexpr (std::is_same_v<Real, float>) {
            if (u == 0 || v == 0 || w == 0) {
                u = float(double(cx) * double(by) - double(cy) * double(bx));
                v = float(double(ax) * double(cy) - double(ay) * double(cx));
                w = float(double(bx) * double(ay) - double(by) * double(ax));
            }
        }
        if ((u < 0 || v < 0 || w < 0) && (u > 0 || v > 0 || w > 0)) return false;
        const Real det = u + v + w;
        if (det == 0) return false;

        const Real az = ray.sz * a[ray.kz];
        const Real bz = ray.sz * b[ray.kz];
        const Real cz = ray.sz * c[ray.kz];
        const Real t_scaled = u * az + v * bz + w * cz;
        const Real inverse_det = Real(1) / det;
        // The interval is checked on the t that is reported: checking t_scaled against the
        // det-scaled interval lets the two further roundings push t an ulp outside it, and
        // then which of two triangles meeting at a vertex is closest depends on test order.
        const Real t = t_scaled * inverse_det;
        if (!(t > t_min && t <= t_max)) return false;
        hit.t = t;
        hit.b1 = v * inverse_det;
        hit.b2 = w * inverse_det;
        return true;
    }
};

}  // namespace prism
