// Axis-aligned bounding box, and the slab test the BVH traversal runs at every node.
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/geometry/ray.hpp>
#include <prism/math/floating_point.hpp>

#include <algorithm>

namespace prism {

template <Scalar Real>
struct Aabb {
    Vec3<Real> min{infinity<Real>};
    Vec3<Real> max{-infinity<Real>};

    static Aabb empty() { return {}; }

    void extend(const Vec3<Real>& p) {
        min = glm::min(min, p);
        max = glm::max(max, p);
    }
    void extend(const Aabb& b) {
        min = glm::min(min, b.min);
        max = glm::max(max, b.max);
    }
    bool is_empty() const { return min.x > max.x || min.y > max.y || min.z > max.z; }
    Vec3<Real> extent() const { return max - min; }
    Vec3<Real> centroid() const { return (min + max) * Real(0.5); }
    Real half_area() const {
        if (is_empty()) return 0;
        const Vec3<Real> e = extent();
        return e.x * e.y + e.y * e.z + e.z * e.x;
    }
    Vec3<Real> corner(int i) const {
        return {(i & 1) ? max.x : min.x, (i & 2) ? max.y : min.y, (i & 4) ? max.z : min.z};
    }
};

// What the slab test needs of a ray, computed once per ray rather than once per node.
template <Scalar Real>
struct RayBoxPrecomputed {
    Vec3<Real> origin;
    Vec3<Real> inverse_direction;

    explicit RayBoxPrecomputed(const Ray<Real>& ray) : origin(ray.origin) {
        // 1/0 = inf is what the slab test wants; -0 gives -inf, which is also right.
        inverse_direction = Vec3<Real>(Real(1)) / ray.direction;
    }
};

// Ize, "Robust BVH Ray Traversal" (JCGT 2013): widening every far slab distance by 1 + 2
// gamma(3) makes the box test conservative, so rounding never culls a box the ray enters. One
// constant for every index that tests boxes (BvhTree, WideBvhTree, SceneIndex's world meshes).
template <Scalar Real>
inline constexpr Real robust_far_scale = Real(1) + 2 * gamma<Real>(3);

// Returns the entry distance, or infinity when the box is missed within [t_min, t_max].
// The min/max ordering makes NaNs (0 * inf on a slab plane) drop out instead of accepting.
// `far_scale` widens each axis's exit distance (Ize, "Robust BVH Ray Traversal", JCGT 2013:
// 1 + 2 gamma(3) makes the test conservative); widening only t_max is not enough, since a ray
// through a box corner can then leave on one axis an ulp before it enters on another.
// Forced inline: GCC's budget for the calling translation unit decides otherwise, and an
// out-of-line call in front of the world-space index took 10% of the dragon's camera rays
// (the merged index is entered after this test, once per ray).
template <Scalar Real>
PRISM_FORCE_INLINE inline Real intersect_box(const Aabb<Real>& box, const RayBoxPrecomputed<Real>& ray, Real t_min, Real t_max,
                          Real far_scale = 1) {
    for (int axis = 0; axis < 3; ++axis) {
        Real t0 = (box.min[axis] - ray.origin[axis]) * ray.inverse_direction[axis];
        Real t1 = (box.max[axis] - ray.origin[axis]) * ray.inverse_direction[axis];
        if (t0 > t1) std::swap(t0, t1);
        t1 *= far_scale;
        t_min = t0 > t_min ? t0 : t_min;
        t_max = t1 < t_max ? t1 : t_max;
    }
    return t_min <= t_max ? t_min : infinity<Real>;
}

}  // namespace prism
