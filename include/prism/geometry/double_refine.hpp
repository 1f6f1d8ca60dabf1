// The double-precision intersection variant: traversal stays in the renderer's precision (float),
// while vertices are stored in double and every ray-triangle test runs the watertight test in
// double. Meant for dense meshes of tiny triangles, where float edge functions and
// determinants lose the hits that double keeps; it costs memory for the vertices and a wider
// test, not a wider traversal.
#pragma once

#include <prism/geometry/watertight.hpp>

namespace prism {

struct DoubleRefine {
    template <Scalar Real> using Storage = double;

    template <Scalar Real>
    struct Prepared {
        Watertight::Prepared<double> ray;
        explicit Prepared(const Ray<Real>& r)
            : ray(Ray<double>{Vec3<double>(r.origin), Vec3<double>(r.direction), double(r.t_min), double(r.t_max)}) {}
    };

    template <Scalar Real>
    static bool intersect(const Prepared<Real>& prepared, const Vec3<double>& p0, const Vec3<double>& p1,
                          const Vec3<double>& p2, Real t_min, Real t_max, TriangleHit<Real>& hit) {
        TriangleHit<double> refined;
        if (!Watertight::intersect(prepared.ray, p0, p1, p2, double(t_min), double(t_max), refined)) return false;
        // Rounding t to Real may land on t_min; the interval test was done in double, where
        // the hit lies strictly beyond it, so keep the hit but never report t below t_min.
        hit.t = Real(refined.t);
        hit.b1 = Real(refined.b1);
        hit.b2 = Real(refined.b2);
        return true;
    }
};

}  // namespace prism
