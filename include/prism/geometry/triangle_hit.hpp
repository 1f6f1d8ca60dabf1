// What a ray-triangle test reports, and the concept every triangle intersector satisfies so a
// BVH can call it at its leaves without knowing which test it is.
#pragma once

#include <prism/geometry/ray.hpp>

#include <concepts>

namespace prism {

template <Scalar Real>
struct TriangleHit {
    Real t = infinity<Real>;
    Real b1 = 0, b2 = 0;  // barycentric weights of the second and third vertex
};

// An intersector prepares per-ray data once (Prepared<Real>), then tests triangles given by
// their three vertices in the intersector's storage precision (Storage<Real>; the double-refine
// variant keeps vertices in double under float traversal).
template <class I, class Real>
concept TriangleIntersector = Scalar<Real> && requires(const typename I::template Prepared<Real>& prepared,
                                                       const Vec3<typename I::template Storage<Real>>& v,
                                                       Real t_min, Real t_max, TriangleHit<Real>& hit,
                                                       const Ray<Real>& ray) {
    typename I::template Prepared<Real>;
    typename I::template Storage<Real>;
    { typename I::template Prepared<Real>(ray) };
    { I::intersect(prepared, v, v, v, t_min, t_max, hit) } -> std::same_as<bool>;
};

}  // namespace prism
