// A binary BVH over bounding boxes, built with binned SAH (Wald 2007, "On fast Construction of
// SAH-based Bounding Volume Hierarchies") in parallel with TBB, and traversed front to back.
// The tree holds no primitives: traversal hands each leaf's range of primitive_indices to a
// callback, so one tree serves triangles of a mesh and instances of a scene alike.
#pragma once

#include <prism/geometry/aabb.hpp>
#include <prism/math/floating_point.hpp>

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <numeric>
#include <span>
#include <vector>

namespace prism {

struct BvhBuildOptions {
    int bin_count = 16;
    std::uint32_t max_leaf_size = 8;
    float traversal_cost = 1.0f;     // relative to one primitive test
    std::uint32_t parallel_threshold = 4096;  // subtrees at least this large build as tasks
};

template <Scalar Real>
struct BvhNode {
    Aabb<Real> bounds;
    std::uint32_t index = 0;  // inner node: first of two adjacent children; leaf: first primitive
    std::uint32_t count = 0;  // primitives in a leaf; 0 marks an inner node
    bool is_leaf() const { return count != 0; }
};

template <Scalar Real>
class BvhTree {
public:
    static constexpr int max_depth = 64;

    BvhTree() = default;

    static BvhTree build(std::span<const Aabb<Real>> boxes, const BvhBuildOptions& options = {}) {
        BvhTree tree;
        const auto count = static_cast<std::uint32_t>(boxes.size());
        tree.primitive_indices_.resize(count);
        std::iota(tree.primitive_indices_.begin(), tree.primitive_indices_.end(), 0u);
        if (count == 0) return tree;
        std::vector<Vec3<Real>> centroids(count);
        Aabb<Real> root_bounds;
        for (std::uint32_t i = 0; i < count; ++i) {
            centroids[i] = boxes[i].centroid();
            root_bounds.extend(boxes[i]);
        }
        tree.nodes_.resize(2 * std::size_t(count) - 1);
        tree.nodes_[0].bounds = root_bounds;
        Builder builder{boxes, centroids, tree.primitive_indices_, tree.nodes_, options, {1}};
        builder.build(0, 0, count, 0);
        tree.nodes_.resize(builder.node_count.load());
        tree.nodes_.shrink_to_fit();
        return tree;
    }

    const std::vector<BvhNode<Real>>& nodes() const { return nodes_; }
    const std::vector<std::uint32_t>& primitive_indices() const { return primitive_indices_; }
    Aabb<Real> bounds() const { return nodes_.empty() ? Aabb<Real>{} : nodes_[0].bounds; }
    int depth() const { return nodes_.empty() ? 0 : depth_of(0); }

    // Closest hit: `leaf(first, count, t_max)` tests primitive_indices[first, first + count),
    // lowering t_max on hits. Children are visited nearest first so t_max prunes early.
    template <class Leaf>
    void traverse_closest(const Ray<Real>& ray, Real& t_max, Leaf&& leaf) const {
        traverse<false>(ray, t_max, leaf);
    }

    // Any hit: stops as soon as `leaf(first, count, t_max)` returns true.
    template <class Leaf>
    bool traverse_any(const Ray<Real>& ray, Real t_max, Leaf&& leaf) const {
        return traverse<true>(ray, t_max, leaf);
    }

private:
    // Ize, "Robust BVH Ray Traversal" (JCGT 2013): widening every far slab distance by 1 + 2
    // gamma(3) makes the box test conservative, so rounding never culls a box the ray enters.
    static constexpr Real far_scale = Real(1) + 2 * gamma<Real>(3);

    static Real enter(const BvhNode<Real>& node, const RayBoxPrecomputed<Real>& ray, Real t_min, Real t_max) {
        return intersect_box(node.bounds, ray, t_min, t_max * far_scale, far_scale);
    }

    template <bool AnyHit, class Leaf>
    bool traverse(const Ray<Real>& ray, Real& t_max, Leaf& leaf) const {
        if (nodes_.empty()) return false;
        const RayBoxPrecomputed<Real> box_ray(ray);
        if (enter(nodes_[0], box_ray, ray.t_min, t_max) == infinity<Real>) return false;
        std::array<std::uint32_t, max_depth> stack;
        int stack_size = 0;
        std::uint32_t current = 0;
        bool found = false;
        for (;;) {
            const BvhNode<Real>& node = nodes_[current];
            if (node.is_leaf()) {
                if (leaf(node.index, node.count, t_max)) {
                    found = true;
                    if constexpr (AnyHit) return true;
                }
            } else {
                const std::uint32_t left = node.index, right = node.index + 1;
                const Real t_left = enter(nodes_[left], box_ray, ray.t_min, t_max);
                const Real t_right = enter(nodes_[right], box_ray, ray.t_min, t_max);
                const bool hit_left = t_left != infinity<Real>, hit_right = t_right != infinity<Real>;
                if (hit_left && hit_right) {
                    const bool left_first = t_left <= t_right;
                    stack[stack_size++] = left_first ? right : left;
                    current = left_first ? left : right;
                    continue;
                }
                if (hit_left || hit_right) {
                    current = hit_left ? left : right;
                    continue;
                }
            }
            if (stack_size == 0) break;
            current = stack[--stack_size];
        }
        return found;
    }

    int depth_of(std::uint32_t i) const {
        const BvhNode<Real>& node = nodes_[i];
        return node.is_leaf() ? 1 : 1 + std::max(depth_of(node.index), depth_of(node.index + 1));
    }

    struct Builder {
        std::span<const Aabb<Real>> boxes;
        const std::vector<Vec3<Real>>& centroids;
        std::vector<std::uint32_t>& indices;
        std::vector<BvhNode<Real>>& nodes;
        const BvhBuildOptions& options;
        std::atomic<std::uint32_t> node_count;

        struct Bin {
            Aabb<Real> bounds;
            std::uint32_t count = 0;
        };

        void make_leaf(std::uint32_t node, std::uint32_t begin, std::uint32_t end) {
            nodes[node].index = begin;
            nodes[node].count = end - begin;
        }

        void build(std::uint32_t node, std::uint32_t begin, std::uint32_t end, int depth) {
            const std::uint32_t count = end - begin;
            // Leave room on the traversal stack: past max_depth - 1, stop splitting.
            if (count <= 1 || depth >= max_depth - 2) return make_leaf(node, begin, end);

            Aabb<Real> centroid_bounds;
            for (std::uint32_t i = begin; i < end; ++i) centroid_bounds.extend(centroids[indices[i]]);

            const int bin_count = options.bin_count;
            int best_axis = -1, best_split = 0;
            Real best_cost = infinity<Real>;
            Aabb<Real> best_left, best_right;
            for (int axis = 0; axis < 3; ++axis) {
                const Real lo = centroid_bounds.min[axis], hi = centroid_bounds.max[axis];
                if (!(hi > lo)) continue;
                const Real scale = Real(bin_count) / (hi - lo);
                std::array<Bin, 64> bins{};
                for (std::uint32_t i = begin; i < end; ++i) {
                    const std::uint32_t p = indices[i];
                    const int b = std::min(bin_count - 1, int((centroids[p][axis] - lo) * scale));
                    bins[b].bounds.extend(boxes[p]);
                    ++bins[b].count;
                }
                // Sweep from the right, then from the left, evaluating every plane between bins.
                std::array<Real, 64> right_cost{};
                std::array<Aabb<Real>, 64> right_bounds{};
                Aabb<Real> accumulated;
                std::uint32_t accumulated_count = 0;
                for (int b = bin_count - 1; b > 0; --b) {
                    accumulated.extend(bins[b].bounds);
                    accumulated_count += bins[b].count;
                    right_bounds[b] = accumulated;
                    right_cost[b] = accumulated.half_area() * Real(accumulated_count);
                }
                accumulated = {};
                accumulated_count = 0;
                for (int b = 0; b < bin_count - 1; ++b) {
                    accumulated.extend(bins[b].bounds);
                    accumulated_count += bins[b].count;
                    const Real cost = accumulated.half_area() * Real(accumulated_count) + right_cost[b + 1];
                    if (accumulated_count > 0 && accumulated_count < count && cost < best_cost) {
                        best_cost = cost;
                        best_axis = axis;
                        best_split = b + 1;
                        best_left = accumulated;
                        best_right = right_bounds[b + 1];
                    }
                }
            }

            const Real node_area = nodes[node].bounds.half_area();
            const Real leaf_cost = Real(count);
            const Real split_cost =
                Real(options.traversal_cost) + (node_area > 0 ? best_cost / node_area : Real(count));
            std::uint32_t middle;
            if (best_axis < 0) {
                // All centroids coincide: SAH cannot separate them; split by count if too many.
                if (count <= options.max_leaf_size) return make_leaf(node, begin, end);
                middle = begin + count / 2;
                best_left = {};
                best_right = {};
                for (std::uint32_t i = begin; i < middle; ++i) best_left.extend(boxes[indices[i]]);
                for (std::uint32_t i = middle; i < end; ++i) best_right.extend(boxes[indices[i]]);
            } else {
                if (count <= options.max_leaf_size && leaf_cost <= split_cost) return make_leaf(node, begin, end);
                const Real lo = centroid_bounds.min[best_axis];
                const Real scale = Real(bin_count) / (centroid_bounds.max[best_axis] - lo);
                const auto in_left = [&](std::uint32_t p) {
                    return std::min(bin_count - 1, int((centroids[p][best_axis] - lo) * scale)) < best_split;
                };
                middle = std::uint32_t(std::partition(indices.begin() + begin, indices.begin() + end, in_left) -
                                       indices.begin());
            }

            const std::uint32_t left = node_count.fetch_add(2);
            nodes[node].index = left;
            nodes[node].count = 0;
            nodes[left].bounds = best_left;
            nodes[left + 1].bounds = best_right;
            if (count >= options.parallel_threshold) {
                tbb::parallel_invoke([&] { build(left, begin, middle, depth + 1); },
                                     [&] { build(left + 1, middle, end, depth + 1); });
            } else {
                build(left, begin, middle, depth + 1);
                build(left + 1, middle, end, depth + 1);
            }
        }
    };

    std::vector<BvhNode<Real>> nodes_;
    std::vector<std::uint32_t> primitive_indices_;
};

}  // namespace prism
