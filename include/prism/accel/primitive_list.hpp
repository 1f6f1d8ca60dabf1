// The brute-force index: every primitive in one leaf. Same interface as BvhTree, so any
// accelerated structure can be checked against it on the same primitives.
#pragma once

#include <prism/geometry/aabb.hpp>

#include <cstdint>
#include <numeric>
#include <span>
#include <vector>

namespace prism {

template <Scalar Real>
class PrimitiveList {
public:
    static PrimitiveList build(std::span<const Aabb<Real>> boxes) {
        PrimitiveList list;
        list.primitive_indices_.resize(boxes.size());
        std::iota(list.primitive_indices_.begin(), list.primitive_indices_.end(), 0u);
        for (const auto& box : boxes) list.bounds_.extend(box);
        return list;
    }

    const std::vector<std::uint32_t>& primitive_indices() const { return primitive_indices_; }
    Aabb<Real> bounds() const { return bounds_; }
    std::size_t memory_bytes() const { return primitive_indices_.capacity() * sizeof(std::uint32_t); }

    template <class Leaf>
    void traverse_closest(const Ray<Real>&, Real& t_max, Leaf&& leaf) const {
        if (!primitive_indices_.empty()) leaf(0u, std::uint32_t(primitive_indices_.size()), t_max);
    }
    template <class Leaf>
    bool traverse_any(const Ray<Real>&, Real t_max, Leaf&& leaf) const {
        return !primitive_indices_.empty() && leaf(0u, std::uint32_t(primitive_indices_.size()), t_max);
    }

    // Nothing to prepare of a ray; the overloads keep the interface of the trees.
    struct TraversalRay {
        explicit TraversalRay(const Ray<Real>&) {}
    };
    template <class Leaf>
    void traverse_closest(const TraversalRay&, Real, Real& t_max, Leaf&& leaf) const {
        if (!primitive_indices_.empty()) leaf(0u, std::uint32_t(primitive_indices_.size()), t_max);
    }
    template <class Leaf>
    bool traverse_any(const TraversalRay&, Real, Real t_max, Leaf&& leaf) const {
        return !primitive_indices_.empty() && leaf(0u, std::uint32_t(primitive_indices_.size()), t_max);
    }

private:
    std::vector<std::uint32_t> primitive_indices_;
    Aabb<Real> bounds_;
};

}  // namespace prism
