// Acceleration policies and the concepts they satisfy. A policy names the spatial index (BVH or
// brute force) and the triangle intersector its leaves call; the geometry built from a policy
// is an Accelerator: closest hit and any hit, nothing more.
#pragma once

#include <prism/accel/bvh_tree.hpp>
#include <prism/accel/primitive_list.hpp>
#include <prism/accel/wide_bvh_tree.hpp>
#include <prism/geometry/ray_batch.hpp>
#include <prism/geometry/triangle_hit.hpp>
#include <prism/geometry/watertight.hpp>

#include <concepts>
#include <span>

namespace prism {

// A spatial index over boxes, traversed with a leaf callback (BvhTree, PrimitiveList).
template <class I, class Real>
concept SpatialIndex = Scalar<Real> && requires(const I& index, std::span<const Aabb<Real>> boxes,
                                                const Ray<Real>& ray, Real t) {
    { I::build(boxes) } -> std::same_as<I>;
    typename I::TraversalRay;  // what traversal prepares of a ray, once (two levels can share it)
    { index.primitive_indices() };
    { index.traverse_any(ray, t, [](std::uint32_t, std::uint32_t, Real&) { return true; }) } -> std::same_as<bool>;
};

// What finds hits: the query seam's two entries (geometry/ray_batch.hpp), closest hits and any
// hits of a batch of rays.
template <class A, class Real>
concept Accelerator = Scalar<Real> && requires(const A& accel, const RayBatch<Real>& batch, Hit<Real>* hits) {
    { accel.intersect(batch, hits) } -> std::same_as<std::uint32_t>;
    { accel.occluded(batch) } -> std::same_as<std::uint32_t>;
};

template <class IntersectorT = Watertight>
struct Bvh {
    using Intersector = IntersectorT;
    template <Scalar Real> using Index = BvhTree<Real>;
};

// The wide BVH: N = 4 or 8 children per node, and leaves of N-wide triangle packets
// (geometry/triangle_packets.hpp) that the policy's meshes keep beside their triangles.
template <class IntersectorT = Watertight, int Width = 8>
struct WideBvh {
    using Intersector = IntersectorT;
    static constexpr int packet_width = Width;
    template <Scalar Real> using Index = WideBvhTree<Real, Width>;
};

template <class IntersectorT = Watertight>
struct BruteForce {
    using Intersector = IntersectorT;
    template <Scalar Real> using Index = PrimitiveList<Real>;
};

template <class P, class Real>
concept AccelerationPolicy = Scalar<Real> && TriangleIntersector<typename P::Intersector, Real> &&
                             SpatialIndex<typename P::template Index<Real>, Real>;

}  // namespace prism
