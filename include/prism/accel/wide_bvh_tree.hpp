// A wide BVH: every node has up to N children (4 or 8) whose boxes are stored SoA, so one SIMD
// slab test (simd/pack.hpp) decides them all (the node: accel/wide_bvh_node.hpp). Built by
// collapsing the binned-SAH binary tree (accel/bvh_tree.hpp) with the surface area heuristic
// (accel/wide_bvh_collapse.hpp). Traversal is nearest first for the closest hit and in stack
// order for any hit; several rays at once take accel/wide_bvh_lanes.hpp. Like BvhTree it holds
// no primitives: a leaf hands its range of primitive_indices to a callback.
//
// Leaves are sized for N-wide triangle packets: a leaf is a binary subtree of at most 2N
// primitives (one or two packets; max_leaf_size when that is below N), and every leaf's range
// starts at a multiple of N, padded up to the next multiple of N with repeats of its last
// primitive. A leaf callback still gets the true count; the padding only lets packet k of a
// mesh be slots [k N, k N + N) (geometry/triangle_packets.hpp).
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/accel/bvh_tree.hpp>
#include <prism/accel/wide_bvh_node.hpp>
#include <prism/memory/huge_page_allocator.hpp>
#include <prism/simd/pack.hpp>
#include <prism/simd/prefetch.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

// Traversal statistics (nodes tested, child boxes entered, leaves, packets and triangles tested)
// for bench/intersect_bench.cpp's counting build, which defines PRISM_TRAVERSAL_STATS; without
// it the counts are not compiled at all, so the kernel is the same code.
#ifdef PRISM_TRAVERSAL_STATS
namespace prism {
struct TraversalStats {
    std::uint64_t nodes = 0, boxes_entered = 0, leaves = 0, packets = 0, triangles = 0;
};
inline thread_local TraversalStats traversal_stats;
}  // namespace prism
#define PRISM_COUNT_NODE(hits) (++::prism::traversal_stats.nodes, ::prism::traversal_stats.boxes_entered += std::popcount(hits))
#define PRISM_COUNT_LEAF(count, n)                                            \
    (++::prism::traversal_stats.leaves, ::prism::traversal_stats.packets += ((count) + (n) - 1) / (n), \
     ::prism::traversal_stats.triangles += (count))
#else
#define PRISM_COUNT_NODE(hits) ((void)0)
#define PRISM_COUNT_LEAF(count, n) ((void)0)
#endif

namespace prism {

template <Scalar Real, int N>
class WideBvhTree {
    static_assert(N == 4 || N == 8, "a wide BVH node has 4 or 8 children");

public:
    static constexpr int width = N;
    // The binary tree's depth limit bounds the collapsed tree's depth too; each level pushes at
    // most N - 1 children.
    static constexpr int stack_size = BvhTree<Real>::max_depth * (N - 1) + 1;

    WideBvhTree() = default;

    // `options.max_leaf_size` (at most N; N by default) bounds the binary tree's leaves; the
    // collapse joins subtrees of up to 2N primitives into a leaf where the heuristic prefers it,
    // unless max_leaf_size is below N, which then bounds every leaf. The top level of a scene
    // asks for 1: an instance costs a transform and a whole BVH, far more
    // than a box test, so each gets a box of its own.
    static WideBvhTree build(std::span<const Aabb<Real>> boxes, BvhBuildOptions options = {.max_leaf_size = N}) {
        return build(static_cast<std::uint32_t>(boxes.size()), [boxes](std::uint32_t i) { return boxes[i]; }, options);
    }

    // The same from `box_of(i)`, the box of primitive i (BvhTree::build's second form).
    template <class BoxOf>
        requires std::is_invocable_r_v<Aabb<Real>, const BoxOf&, std::uint32_t>
    static WideBvhTree build(std::uint32_t count, const BoxOf& box_of, BvhBuildOptions options = {.max_leaf_size = N}) {
        options.max_leaf_size = std::clamp<std::uint32_t>(options.max_leaf_size, 1, N);
        options.leaf_at_max_size = true;  // the collapse would make such a subtree one leaf
        const BvhTree<Real> binary = BvhTree<Real>::build(count, box_of, options);
        WideBvhTree tree;
        if (count == 0) return tree;
        tree.bounds_ = binary.bounds();
        Collapser collapser{binary, tree, options.max_leaf_size, {}, {}, {}, {}};
        collapser.ranges.resize(binary.nodes().size());
        collapser.measure(0);
        collapser.cost.resize(binary.nodes().size() * N);
        collapser.split.resize(binary.nodes().size() * N, 0);  // a leaf's entries are read, not written
        collapser.as_leaf.resize(binary.nodes().size());
        // A mesh's leaf may take two packets where that is cheaper than another child: the
        // bottom of the tree then has fewer nodes. A top level keeps its own limit.
        collapser.leaf_limit = options.max_leaf_size == N ? 2 * N : options.max_leaf_size;
        collapser.plan(0);
        if (binary.nodes()[0].is_leaf()) {
            // One leaf: a root with a single child keeps traversal uniform.
            const std::uint32_t root = tree.new_node();
            collapser.fill_child(root, 0, 0);
        } else {
            collapser.collapse(0);
        }
        tree.primitive_indices_.shrink_to_fit();
        return tree;
    }

    // A tree laid out elsewhere, exactly as build() lays its own out (root at node 0, leaf ranges
    // starting at multiples of N and padded with repeats): bench/intersect_bench.cpp runs this
    // kernel on trees built by Embree's builder, to tell the tree's share of the time from the
    // kernel's.
    static WideBvhTree from_layout(std::span<const WideBvhNode<Real, N>> nodes, std::vector<std::uint32_t> primitive_indices,
                                   Aabb<Real> bounds) {
        WideBvhTree tree;
        tree.nodes_.assign(nodes.begin(), nodes.end());
        tree.primitive_indices_ = std::move(primitive_indices);
        tree.bounds_ = bounds;
        return tree;
    }

    std::span<const WideBvhNode<Real, N>> nodes() const { return nodes_; }
    // Leaf ranges padded to multiples of N (see the top of this file).
    const std::vector<std::uint32_t>& primitive_indices() const { return primitive_indices_; }
    Aabb<Real> bounds() const { return bounds_; }
    std::size_t memory_bytes() const {
        return nodes_.capacity() * sizeof(WideBvhNode<Real, N>) + primitive_indices_.capacity() * sizeof(std::uint32_t);
    }

private:
    using Pack = simd::Pack<Real, N>;
    // Ize's conservative far distance, as in BvhTree: every exit distance times 1 + 2 gamma(3).
    static constexpr Real far_scale = robust_far_scale<Real>;

public:
    // What the slab test needs of a ray, broadcast once. A two-level scene whose mesh shares
    // the world's space prepares it once per ray for both levels (geometry/scene_geometry.hpp).
    struct TraversalRay {
        // far_inverse_direction is inverse_direction times Ize's far_scale, rounded: the
        // widening is paid once per ray instead of once per node (see enter).
        Pack origin[3], inverse_direction[3], far_inverse_direction[3];
        // Where the entered and the left plane of each axis start in WideBvhNode::bounds, by
        // the direction's sign: row times N, an offset the loads add without a multiply.
        std::ptrdiff_t near_plane[3], far_plane[3];

        // Forced inline: GCC's inlining of it into the instanced meshes' top-level traversal
        // came and went with changes elsewhere in the renderer's translation unit (a call for
        // every ray into an instance: 0.5% of hw3 metal_plates_area's instructions).
        explicit PRISM_FORCE_INLINE TraversalRay(const Ray<Real>& ray) {
            const RayBoxPrecomputed<Real> box_ray(ray);
            for (int axis = 0; axis < 3; ++axis) {
                origin[axis] = Pack::broadcast(box_ray.origin[axis]);
                inverse_direction[axis] = Pack::broadcast(box_ray.inverse_direction[axis]);
                far_inverse_direction[axis] = Pack::broadcast(box_ray.inverse_direction[axis] * far_scale);
                // The sign decides which plane is entered, so no per-child min/max: the same
                // order the scalar test's swap finds (1/-0 = -inf enters by the high plane).
                const bool negative = std::signbit(box_ray.inverse_direction[axis]);
                near_plane[axis] = (negative ? 3 + axis : axis) * N;
                far_plane[axis] = (negative ? axis : 3 + axis) * N;
            }
        }
    };

    template <class Leaf>
    void traverse_closest(const Ray<Real>& ray, Real& t_max, Leaf&& leaf) const {
        traverse<false>(TraversalRay(ray), ray.t_min, t_max, leaf);
    }
    template <class Leaf>
    void traverse_closest(const TraversalRay& ray, Real t_min, Real& t_max, Leaf&& leaf) const {
        traverse<false>(ray, t_min, t_max, leaf);
    }
    // The same, calling touch(first) for a leaf that is entered but not tested at once, so
    // that its primitives can be prefetched while nearer children are tested. A touch that only
    // prefetches must be forced inline (PRISM_PREFETCH_INLINE, simd/prefetch.hpp), or GCC drops it.
    template <class Leaf, class Touch>
    void traverse_closest(const TraversalRay& ray, Real t_min, Real& t_max, Leaf&& leaf, Touch&& touch) const {
        traverse<false>(ray, t_min, t_max, leaf, touch);
    }

    template <class Leaf>
    bool traverse_any(const Ray<Real>& ray, Real t_max, Leaf&& leaf) const {
        return traverse<true>(TraversalRay(ray), ray.t_min, t_max, leaf);
    }
    template <class Leaf>
    bool traverse_any(const TraversalRay& ray, Real t_min, Real t_max, Leaf&& leaf) const {
        return traverse<true>(ray, t_min, t_max, leaf);
    }
    template <class Leaf, class Touch>
    bool traverse_any(const TraversalRay& ray, Real t_min, Real t_max, Leaf&& leaf, Touch&& touch) const {
        return traverse<true>(ray, t_min, t_max, leaf, touch);
    }

    // Several rays at once, each ray's answer the one it gets alone (accel/wide_bvh_lanes.hpp):
    // any hits (a row's shadow rays to one light), closest hits (a pixel's camera rays), and
    // which of the rays enter each child of a node.
    template <class Leaf>
    std::uint32_t traverse_any_lanes(const TraversalRay* slabs, const Real* t_min, const Real* t_max, std::uint32_t lanes,
                                     Leaf&& leaf) const;
    template <class Leaf>
    std::uint32_t traverse_closest_lanes(const TraversalRay* slabs, const Real* t_min, Real* t_max, std::uint32_t lanes,
                                         Leaf&& leaf) const;
    template <class Each>
    PRISM_FORCE_INLINE static std::array<std::uint32_t, N> children_entered(const WideBvhNode<Real, N>& node,
                                                                                 const TraversalRay* slabs, const Real* t_min,
                                                                                 const Real* far_limit, std::uint32_t lanes,
                                                                                 Each&& each);
    // The 8x8 bit matrix whose row i is byte i of x, transposed.
    static constexpr std::uint64_t transpose_bits(std::uint64_t x);

    // Whether the ray enters any of the root's children within [t_min, t_max]: the first test
    // traversal makes, and the one a two-level scene makes before it prepares the triangle
    // test's set-up for the tree (geometry/scene_geometry.hpp). With the traversal ray's
    // reciprocals it costs no division, where a box test of its own would divide again; and
    // its eight boxes reject more rays than their union would.
    PRISM_FORCE_INLINE bool enters(const TraversalRay& ray, Real t_min, Real t_max) const {
        if (nodes_.empty()) return false;
        Pack entry;
        return enter(nodes_[0], ray, t_min, t_max * far_scale, entry).any();
    }

private:

    // Every child's entry distance; the mask says which children the ray enters within
    // [t_min, t_max], given as t_min and far_limit = t_max * far_scale. A NaN distance (0 * inf,
    // a ray in a slab's plane) constrains nothing, as in the scalar intersect_box.
    // Ize's widening sits in the ray's far_inverse_direction, not in a multiply here: the node
    // test is one latency chain from the node's load to the hit mask, which the next node's
    // address waits on, and a multiply of the nearest exit added four cycles to it. Each exit
    // distance is fl(fl(plane - origin) * fl(inverse_direction * far_scale)) instead of
    // fl(fl(fl(plane - origin) * inverse_direction) * far_scale): two roundings of the same
    // exact product either way, so the relative error bound that makes the test conservative
    // (intersect_box's) holds unchanged; and t_max is widened as before, by one rounded product.
    PRISM_FORCE_INLINE static simd::Mask<Real, N> enter(const WideBvhNode<Real, N>& node, const TraversalRay& ray, Real t_min,
                                                            Real far_limit, Pack& entry) {
        const Real* planes = &node.bounds[0][0];
        Pack t_enter = Pack::broadcast(t_min);
        Pack t_exit = Pack::broadcast(far_limit);
        for (int axis = 0; axis < 3; ++axis) {
            const Pack t_near = (Pack::load(planes + ray.near_plane[axis]) - ray.origin[axis]) * ray.inverse_direction[axis];
            const Pack t_far = (Pack::load(planes + ray.far_plane[axis]) - ray.origin[axis]) * ray.far_inverse_direction[axis];
            t_enter = simd::max_keep(t_near, t_enter);
            t_exit = simd::min_keep(t_far, t_exit);
        }
        entry = t_enter;
        return t_enter <= t_exit;
    }

    using Node = WideBvhNode<Real, N>;

    struct StackEntry {
        std::uint64_t child;  // the node's child word
        Real distance;        // where the ray enters its box
    };

    const Node& node_at(std::uint64_t offset) const {
        return *reinterpret_cast<const Node*>(reinterpret_cast<const char*>(nodes_.data()) + offset);
    }

    struct NoTouch {
        void operator()(std::uint32_t) const {}
    };

    // A child pushed on the stack is popped only after the nearer ones: its memory is requested
    // now (the node, or through `touch` the leaf's primitives) so that the wait overlaps them.
    template <class Touch>
    PRISM_FORCE_INLINE void prefetch(const StackEntry& entry, Touch& touch) const {
        if (!Node::is_leaf_word(entry.child))
            simd::prefetch(node_at(entry.child));
        else
            touch(Node::leaf_first(entry.child));
    }

    template <bool AnyHit, class Leaf, class Touch = NoTouch>
    bool traverse(const TraversalRay& slabs, Real t_min, Real& t_max, Leaf& leaf, Touch touch = {}) const {
        if (nodes_.empty()) return false;
        std::array<StackEntry, stack_size> stack;
        int size = 0;
        bool found = false;
        alignas(64) Real distances[N];
        std::uint64_t current = 0;  // the byte offset of the inner node to test next (the root's: 0)
        // t_max widened as the box test widens exits, updated only when a leaf shortens t_max:
        // the pops compare with it, and the node test starts from it.
        Real far_limit = t_max * far_scale;
        for (;;) {
            const Node& node = node_at(current);
            simd::prefetch(node);
            Pack entry_distances;
            std::uint32_t hits = enter(node, slabs, t_min, far_limit, entry_distances).bits();
            PRISM_COUNT_NODE(hits);
            bool descend = false;
            if (hits != 0 && (hits & (hits - 1)) == 0) {
                // One child entered, the common case deep in the tree: no stack, no sort.
                const std::uint64_t word = node.child[std::countr_zero(hits)];
                if (!Node::is_leaf_word(word)) {
                    current = word;
                    continue;
                }
                PRISM_COUNT_LEAF(Node::leaf_count(word), N);
                if (leaf(Node::leaf_first(word), Node::leaf_count(word), t_max)) {
                    found = true;
                    if constexpr (AnyHit) return true;
                    far_limit = t_max * far_scale;
                }
            } else if (AnyHit && hits != 0) {
                // Two or more entered, any hit: every entered leaf is tested before any inner
                // child is descended. A shadow ray ends at its first blocker, and a leaf here is
                // one or two packet tests, where an inner child is a subtree; the inner children
                // are pushed in slot order (no distances: any blocker ends the ray).
                std::uint32_t inner = 0;
                while (hits != 0) {
                    const int i = std::countr_zero(hits);
                    hits &= hits - 1;
                    const std::uint64_t word = node.child[i];
                    if (!Node::is_leaf_word(word)) {
                        inner |= std::uint32_t(1) << i;
                        simd::prefetch(node_at(word));
                    } else if (PRISM_COUNT_LEAF(Node::leaf_count(word), N),
                               leaf(Node::leaf_first(word), Node::leaf_count(word), t_max)) {
                        return true;
                    }
                }
                if (inner != 0) {
                    // The last inner child is descended at once, the others wait on the stack.
                    const int last = 31 - std::countl_zero(inner);
                    inner &= ~(std::uint32_t(1) << last);
                    while (inner != 0) {
                        const int i = std::countr_zero(inner);
                        inner &= inner - 1;
                        stack[size++] = StackEntry{node.child[i], Real(0)};
                    }
                    current = node.child[last];
                    continue;
                }
            } else if (const std::uint32_t rest = hits & (hits - 1); hits != 0 && (rest & (rest - 1)) == 0) {
                // Two children entered: one comparison orders them. The nearer is descended at
                // once, or pushed last if it is a leaf; on a tie the second child goes first,
                // as the ranks below order them (which triangle wins a tie depends on
                // the order).
                entry_distances.store(distances);
                const int first = std::countr_zero(hits), second = std::countr_zero(rest);
                int near = second, far = first;
                if constexpr (!AnyHit) {
                    if (distances[first] < distances[second]) std::swap(near, far);
                }
                stack[size++] = StackEntry{node.child[far], distances[far]};
                prefetch(stack[size - 1], touch);
                if (!Node::is_leaf_word(node.child[near])) {
                    current = node.child[near];
                    continue;
                }
                stack[size++] = StackEntry{node.child[near], distances[near]};
            } else if (hits != 0) {
                // Three or more entered (closest hit): each child's place on the stack is its
                // rank, counted with two SIMD compares against every entered distance, so the
                // order costs no data-dependent branch (an insertion sort mispredicts on about
                // every other move). Farther children go lower; of equal distances the lower
                // slot goes lower, so the higher slot is popped first, as the insertion sort
                // this replaced ordered them (which triangle wins a tie depends on the order).
                entry_distances.store(distances);
                const std::uint32_t entered = hits;
                while (hits != 0) {
                    const int i = std::countr_zero(hits);
                    hits &= hits - 1;
                    const Pack own = Pack::broadcast(distances[i]);
                    const std::uint32_t below =
                        ((own < entry_distances).bits() | ((own == entry_distances).bits() & ((std::uint32_t(1) << i) - 1))) &
                        entered;
                    StackEntry& pushed = stack[size + std::popcount(below)];
                    pushed = StackEntry{node.child[i], distances[i]};
                    prefetch(pushed, touch);
                }
                size += std::popcount(entered);
            }
            // Pop until an inner node to descend into; leaves on the way are tested at once.
            while (size > 0) {
                // Read in place: a copy went through a stack temporary (two store-to-load
                // forwards on the way to the next node's address).
                const StackEntry& entry = stack[--size];
                // A box entered beyond the closest hit so far cannot hold a closer one (compared
                // with the widened t_max the box test itself uses).
                if constexpr (!AnyHit) {
                    if (entry.distance > far_limit) continue;
                }
                if (!Node::is_leaf_word(entry.child)) {
                    current = entry.child;
                    descend = true;
                    break;
                }
                PRISM_COUNT_LEAF(Node::leaf_count(entry.child), N);
                if (leaf(Node::leaf_first(entry.child), Node::leaf_count(entry.child), t_max)) {
                    found = true;
                    if constexpr (AnyHit) return true;
                    far_limit = t_max * far_scale;
                }
            }
            if (!descend) return found;
        }
    }

    std::uint32_t new_node() {
        nodes_.push_back(WideBvhNode<Real, N>::empty());
        return std::uint32_t(nodes_.size() - 1);
    }

    // The binary tree's collapse into wide nodes (accel/wide_bvh_collapse.hpp).
    struct Collapser;

    // In transparent huge pages where they fill one (memory/huge_page_allocator.hpp), as the
    // leaves' packets are: a large mesh's traversal reads nodes all over the array, and in 4 kB
    // pages the dragon's per-ray time against Embree (which asks for huge pages itself) swung
    // between runs (bench/RESULTS.md, "Per ray against Embree").
    HugePageVector<WideBvhNode<Real, N>> nodes_;
    std::vector<std::uint32_t> primitive_indices_;
    Aabb<Real> bounds_;
};

}  // namespace prism

#include <prism/accel/wide_bvh_collapse.hpp>
#include <prism/accel/wide_bvh_lanes.hpp>
