// A wide BVH: every node has up to N children (4 or 8) whose boxes are stored SoA, so one SIMD
// slab test (simd/pack.hpp) decides them all. Built by collapsing the binned-SAH binary tree
// (accel/bvh_tree.hpp) with the surface area heuristic: for every binary subtree, the cheapest
// way to spread it over 1..N child slots is found bottom up (dynamic programming, as Ylitie,
// Karras and Laine 2017 collapse into their compressed wide BVH), and each wide node takes the
// cheapest spread of its binary node's two subtrees over all N slots. Opening the largest-area
// child until N children are found (Wald, Benthin, Boulos 2008) had left 4.3 children per node
// on the tiny-triangle dragon; this collapse gives 7.4 and 8-10% faster rays (bench/RESULTS.md).
// Traversal is nearest first for the closest hit and in stack order for any hit. Like BvhTree it
// holds no primitives: a leaf hands its range of primitive_indices to a callback.
//
// Leaves are sized for N-wide triangle packets: a leaf is a binary subtree of at most 2N
// primitives (one or two packets; max_leaf_size when that is below N), and every leaf's range
// starts at a multiple of N, padded up to the next multiple of N with repeats of its last
// primitive. A leaf callback still gets the true count; the padding only lets packet k of a
// mesh be slots [k N, k N + N) (geometry/triangle_packets.hpp).
#pragma once

#include <prism/accel/bvh_tree.hpp>
#include <prism/memory/huge_page_allocator.hpp>
#include <prism/simd/pack.hpp>
#include <prism/simd/prefetch.hpp>

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
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
struct alignas(64) WideBvhNode {
    // bounds[axis][child] is the low plane, bounds[3 + axis][child] the high one. An empty
    // child slot is the empty box (low +inf, high -inf): entered at +inf and left at -inf
    // whatever the direction's sign, it is missed even by a ray with t_max = inf.
    Real bounds[6][N];
    // Each child in one word, as Embree's tagged node references: one load and one register
    // per child on the way down, and a test of its lowest bit tells a leaf. An inner child is
    // its node's byte offset in the tree's node array (a multiple of the node's size, so its
    // lowest bit is 0), which traversal adds to the array's address as it is, with no shift on
    // the way to the next node's load; a leaf is first << 32 | count << 1 | 1, first its first
    // slot in primitive_indices and count its primitives (any count: a leaf of primitives that
    // cannot be split, such as many equal boxes, may hold hundreds). An empty slot holds 0.
    // Eight 64-bit words fill the fourth line of an 8-wide float node, which the two arrays
    // of 32-bit child indices and counts filled before: the node stays 256 bytes.
    std::uint64_t child[N];

    // A node of N empty slots, filled child by child by a builder.
    static WideBvhNode empty() {
        WideBvhNode node;
        for (int row = 0; row < 6; ++row)
            for (Real& plane : node.bounds[row]) plane = row < 3 ? infinity<Real> : -infinity<Real>;
        for (int i = 0; i < N; ++i) node.child[i] = 0;
        return node;
    }

    static constexpr bool is_leaf_word(std::uint64_t word) { return (word & 1) != 0; }
    static constexpr std::uint32_t leaf_first(std::uint64_t word) { return std::uint32_t(word >> 32); }
    static constexpr std::uint32_t leaf_count(std::uint64_t word) { return std::uint32_t(word) >> 1; }
    // Leaf: its primitive count; inner child or empty slot: 0.
    std::uint32_t count(int i) const { return is_leaf_word(child[i]) ? leaf_count(child[i]) : 0; }
    // Inner child: its node's index; leaf: its first slot in primitive_indices.
    std::uint32_t index(int i) const {
        return is_leaf_word(child[i]) ? leaf_first(child[i]) : std::uint32_t(child[i] / sizeof(WideBvhNode));
    }
    void set_inner(int i, std::uint32_t node) { child[i] = std::uint64_t(node) * sizeof(WideBvhNode); }
    void set_leaf(int i, std::uint32_t first, std::uint32_t primitives) {
        if (primitives == 0 || primitives > (UINT32_MAX >> 1)) throw std::length_error("WideBvhTree: a leaf of 0 or 2^31 primitives");
        child[i] = std::uint64_t(first) << 32 | std::uint64_t(primitives) << 1 | 1;
    }
};
static_assert(sizeof(WideBvhNode<float, 8>) == 256, "an 8-wide float node is four cache lines");

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
    static WideBvhTree from_layout(std::vector<WideBvhNode<Real, N>> nodes, std::vector<std::uint32_t> primitive_indices,
                                   Aabb<Real> bounds) {
        WideBvhTree tree;
        tree.nodes_ = std::move(nodes);
        tree.primitive_indices_ = std::move(primitive_indices);
        tree.bounds_ = bounds;
        return tree;
    }

    const std::vector<WideBvhNode<Real, N>>& nodes() const { return nodes_; }
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

        explicit TraversalRay(const Ray<Real>& ray) {
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

    // Any hit for several rays at once (bit i of `lanes` for ray i, i < 32: a row's shadow rays
    // to one light), each ray's answer traverse_any's: a ray is tested at a node only if it
    // entered that node's box, with its own slab set-up (`slabs[i]`) and the node test
    // traverse_any makes, so each ray reaches exactly the leaves it would reach alone. Only the
    // order of the visits differs, which an any-hit answer does not depend on.
    // leaf(first, count, lanes) tests the leaf's primitives for the rays of `lanes` and returns
    // the blocked ones; the answer is every blocked ray.
    // The rays' node tests are independent of each other: where one ray waits on each node's
    // test before it can load the next node, the tests of the rays that reach a node overlap.
    template <class Leaf>
    std::uint32_t traverse_any_lanes(const TraversalRay* slabs, const Real* t_min, const Real* t_max, std::uint32_t lanes,
                                     Leaf&& leaf) const {
        if (nodes_.empty() || lanes == 0) return 0;
        struct LaneEntry {
            std::uint64_t child;
            std::uint32_t lanes;
        };
        std::array<LaneEntry, stack_size> stack;
        alignas(64) Real far_limit[32];
        for (std::uint32_t rest = lanes; rest != 0; rest &= rest - 1) {
            const int i = std::countr_zero(rest);
            far_limit[i] = t_max[i] * far_scale;
        }
        int size = 0;
        std::uint32_t blocked = 0;
        std::uint64_t current = 0;
        std::uint32_t current_lanes = lanes;
        for (;;) {
            const Node& node = node_at(current);
            const std::array<std::uint32_t, N> entering =
                children_entered(node, slabs, t_min, far_limit, current_lanes, [](int, const auto&, const Pack&) {});
            // The leaves first, as traverse_any tests them: a shadow ray ends at its first blocker.
            std::uint32_t inner = 0;
            for (int c = 0; c < N; ++c) {
                if (entering[std::size_t(c)] == 0) continue;
                const std::uint64_t word = node.child[c];
                if (!Node::is_leaf_word(word)) {
                    inner |= std::uint32_t(1) << c;
                    continue;
                }
                const std::uint32_t testing = entering[std::size_t(c)] & ~blocked;
                if (testing == 0) continue;
                PRISM_COUNT_LEAF(Node::leaf_count(word), N);
                blocked |= leaf(Node::leaf_first(word), Node::leaf_count(word), testing) & testing;
            }
            if (blocked == lanes) return blocked;
            bool descend = false;
            if (inner != 0) {
                const int last = 31 - std::countl_zero(inner);
                inner &= ~(std::uint32_t(1) << last);
                for (; inner != 0; inner &= inner - 1) {
                    const int c = std::countr_zero(inner);
                    stack[size++] = LaneEntry{node.child[c], entering[std::size_t(c)]};
                    simd::prefetch(node_at(node.child[c]));
                }
                const std::uint32_t next = entering[std::size_t(last)] & ~blocked;
                if (next != 0) {
                    current = node.child[last];
                    current_lanes = next;
                    descend = true;
                }
            }
            while (!descend && size > 0) {
                const LaneEntry& entry = stack[--size];
                const std::uint32_t next = entry.lanes & ~blocked;
                if (next == 0) continue;
                current = entry.child;
                current_lanes = next;
                descend = true;
            }
            if (!descend) return blocked;
        }
    }

    // Closest hits for several rays at once (bit i of `lanes` for ray i, i < 32: a pixel's
    // camera rays), each ray tested at a node only if it entered that node's box within its own
    // current t_max, with its own slab set-up and traverse's node test, so each ray reaches
    // every leaf that could hold a hit nearer than the one it has. The leaves are visited in
    // one order for all the rays (nearest first by the nearest entry among them), not each
    // ray's own: the closest hit is the same wherever it is unique, and the caller decides what
    // a tie means (TriangleMesh::intersect_lanes).
    // leaf(first, count, lanes) tests the leaf's primitives for the rays of `lanes`, lowers
    // t_max[i] for each ray it hits and returns those rays; the answer is every ray hit.
    template <class Leaf>
    std::uint32_t traverse_closest_lanes(const TraversalRay* slabs, const Real* t_min, Real* t_max, std::uint32_t lanes,
                                         Leaf&& leaf) const {
        if (nodes_.empty() || lanes == 0) return 0;
        struct LaneEntry {
            std::uint64_t child;
            std::uint32_t lanes;
            Real nearest;  // the nearest entry of its rays into its box
        };
        std::array<LaneEntry, stack_size> stack;
        alignas(64) Real far_limit[32];
        Real farthest = 0;  // the largest far_limit of the rays: an entry beyond it is no ray's
        for (std::uint32_t rest = lanes; rest != 0; rest &= rest - 1) {
            const int i = std::countr_zero(rest);
            far_limit[i] = t_max[i] * far_scale;
            farthest = std::max(farthest, far_limit[i]);
        }
        const auto after_hits = [&](std::uint32_t hit) {
            if (hit == 0) return;
            for (std::uint32_t rest = hit; rest != 0; rest &= rest - 1) {
                const int i = std::countr_zero(rest);
                far_limit[i] = t_max[i] * far_scale;
            }
            farthest = 0;
            for (std::uint32_t rest = lanes; rest != 0; rest &= rest - 1) farthest = std::max(farthest, far_limit[std::countr_zero(rest)]);
        };
        int size = 0;
        std::uint32_t found = 0;
        std::uint64_t current = 0;
        std::uint32_t current_lanes = lanes;
        for (;;) {
            const Node& node = node_at(current);
            // Per child, the rays that enter it and the nearest entry among them.
            Pack nearest = Pack::broadcast(infinity<Real>);
            const std::array<std::uint32_t, N> entering = children_entered(
                node, slabs, t_min, far_limit, current_lanes,
                [&](int, const auto& entered, const Pack& entry) { nearest = select(entered, simd::min_keep(entry, nearest), nearest); });
            // The entered children pushed farthest first, so that the nearest is popped first.
            alignas(64) Real distances[N];
            nearest.store(distances);
            std::uint32_t children = 0;
            for (int c = 0; c < N; ++c)
                if (entering[std::size_t(c)] != 0) children |= std::uint32_t(1) << c;
            const int first_pushed = size;
            for (std::uint32_t rest = children; rest != 0; rest &= rest - 1) {
                const int c = std::countr_zero(rest);
                int place = first_pushed;
                while (place < size && stack[std::size_t(place)].nearest >= distances[c]) ++place;
                for (int k = size; k > place; --k) stack[std::size_t(k)] = stack[std::size_t(k - 1)];
                stack[std::size_t(place)] = LaneEntry{node.child[c], entering[std::size_t(c)], distances[c]};
                ++size;
            }
            // Pop until an inner node to descend into; leaves on the way are tested at once.
            bool descend = false;
            while (size > 0) {
                const LaneEntry entry = stack[std::size_t(--size)];
                if (entry.nearest > farthest) continue;
                if (!Node::is_leaf_word(entry.child)) {
                    current = entry.child;
                    current_lanes = entry.lanes;
                    descend = true;
                    break;
                }
                PRISM_COUNT_LEAF(Node::leaf_count(entry.child), N);
                const std::uint32_t hit =
                    leaf(Node::leaf_first(entry.child), Node::leaf_count(entry.child), entry.lanes) & entry.lanes;
                found |= hit;
                after_hits(hit);
            }
            if (!descend) return found;
        }
    }

    // Which rays of `lanes` enter each child of `node` (bit i of entering[c] for ray i), each
    // by its own node test (enter, with its own slab set-up, t_min and far_limit); `each(i,
    // mask, entry)` sees each ray's test. The rays' hit masks are the rows of a bit matrix (byte
    // i % 8 of rows[i / 8] for ray i), transposed eight by eight into the children's ray masks,
    // with no branch on any ray's hits (a loop over each ray's hit bits mispredicted at about
    // every node).
    template <class Each>
    [[gnu::always_inline]] static std::array<std::uint32_t, N> children_entered(const WideBvhNode<Real, N>& node,
                                                                                 const TraversalRay* slabs, const Real* t_min,
                                                                                 const Real* far_limit, std::uint32_t lanes,
                                                                                 Each&& each) {
        std::array<std::uint64_t, 4> rows{};
        for (std::uint32_t rest = lanes; rest != 0; rest &= rest - 1) {
            const int i = std::countr_zero(rest);
            Pack entry;
            const auto entered = enter(node, slabs[i], t_min[i], far_limit[i], entry);
            each(i, entered, entry);
            rows[std::size_t(i >> 3)] |= std::uint64_t(entered.bits()) << (8 * (i & 7));
        }
        std::array<std::uint32_t, N> entering{};
        for (int group = 0; group < 4; ++group) {
            if (rows[std::size_t(group)] == 0) continue;
            const std::uint64_t columns = transpose_bits(rows[std::size_t(group)]);
            for (int c = 0; c < N; ++c)
                entering[std::size_t(c)] |= std::uint32_t((columns >> (8 * c)) & 0xff) << (8 * group);
        }
        return entering;
    }

    // The 8x8 bit matrix whose row i is byte i of x, transposed (bit c of byte i becomes bit i
    // of byte c): three exchanges of 2x2 blocks of growing size (Warren, Hacker's Delight 7-3).
    static constexpr std::uint64_t transpose_bits(std::uint64_t x) {
        std::uint64_t t = (x ^ (x >> 7)) & 0x00AA00AA00AA00AAull;
        x ^= t ^ (t << 7);
        t = (x ^ (x >> 14)) & 0x0000CCCC0000CCCCull;
        x ^= t ^ (t << 14);
        t = (x ^ (x >> 28)) & 0x00000000F0F0F0F0ull;
        x ^= t ^ (t << 28);
        return x;
    }

    // Whether the ray enters any of the root's children within [t_min, t_max]: the first test
    // traversal makes, and the one a two-level scene makes before it prepares the triangle
    // test's set-up for the tree (geometry/scene_geometry.hpp). With the traversal ray's
    // reciprocals it costs no division, where a box test of its own would divide again; and
    // its eight boxes reject more rays than their union would.
    [[gnu::always_inline]] bool enters(const TraversalRay& ray, Real t_min, Real t_max) const {
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
    [[gnu::always_inline]] static simd::Mask<Real, N> enter(const WideBvhNode<Real, N>& node, const TraversalRay& ray, Real t_min,
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
    [[gnu::always_inline]] void prefetch(const StackEntry& entry, Touch& touch) const {
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

    struct Collapser {
        const BvhTree<Real>& binary;
        WideBvhTree& tree;
        std::uint32_t max_leaf_size;
        struct Range {
            std::uint32_t begin, end;
        };
        // Written whole before they are read: not cleared, and in huge pages (accel/bvh_tree.hpp).
        HugePageVector<Range> ranges;  // each binary node's contiguous range of primitive_indices
        // The cheapest way to hold each binary subtree in k child slots, k = 1..N, in the surface
        // area heuristic's units: a node test costs its box's half area, a leaf its box's half
        // area per packet (a packet test and a node test take about as long: both are one SIMD
        // pass over N lanes, and costing packets at 0.5 or 2 times a node made the same trees
        // within 1% of nodes).
        HugePageVector<double> cost;           // [node * N + k - 1]
        HugePageVector<std::uint8_t> split;    // slots given to the left child; 0: one slot holds it all
        HugePageVector<std::uint8_t> as_leaf;  // the one-slot form is a leaf
        std::uint32_t leaf_limit = 0;

        // measure and plan write only their own subtree's entries, so the two subtrees of a
        // node near the root go to two tasks: the same tables, made on every thread there is.
        // In trees of at least parallel_from primitives, nodes fewer than parallel_depth levels
        // from the root fork (up to 2^parallel_depth tasks); smaller trees take one thread.
        static constexpr int parallel_depth = 6;
        static constexpr std::size_t parallel_from = 16384;
        bool forks(int depth) const { return depth < parallel_depth && binary.primitive_indices().size() >= parallel_from; }

        Range measure(std::uint32_t i, int depth = 0) {
            const BvhNode<Real>& node = binary.nodes()[i];
            if (node.is_leaf()) return ranges[i] = {node.index, node.index + node.count};
            Range left, right;
            if (forks(depth)) {
                tbb::parallel_invoke([&] { left = measure(node.index, depth + 1); },
                                     [&] { right = measure(node.index + 1, depth + 1); });
            } else {
                left = measure(node.index, depth + 1);
                right = measure(node.index + 1, depth + 1);
            }
            return ranges[i] = {left.begin, right.end};
        }

        double& slots_cost(std::uint32_t i, int k) { return cost[std::size_t(i) * N + std::size_t(k - 1)]; }

        void plan(std::uint32_t i, int depth = 0) {
            const BvhNode<Real>& node = binary.nodes()[i];
            const double area = double(node.bounds.half_area());
            const std::uint32_t count = ranges[i].end - ranges[i].begin;
            const double leaf = area * double((count + N - 1) / N);
            if (node.is_leaf()) {
                as_leaf[i] = 1;
                for (int k = 1; k <= N; ++k) slots_cost(i, k) = leaf;
                return;
            }
            const std::uint32_t left = node.index, right = node.index + 1;
            if (forks(depth)) {
                tbb::parallel_invoke([&] { plan(left, depth + 1); }, [&] { plan(right, depth + 1); });
            } else {
                plan(left, depth + 1);
                plan(right, depth + 1);
            }
            // best[k]: the children's subtrees spread over k >= 2 slots.
            std::array<double, N + 1> best{};
            for (int k = 2; k <= N; ++k) {
                best[k] = infinity<double>;
                for (int j = 1; j < k; ++j) {
                    const double spread = slots_cost(left, j) + slots_cost(right, k - j);
                    if (spread < best[k]) {
                        best[k] = spread;
                        split[std::size_t(i) * N + std::size_t(k - 1)] = std::uint8_t(j);
                    }
                }
            }
            const double inner = area + best[N];
            const bool leaf_allowed = count <= leaf_limit;
            as_leaf[i] = leaf_allowed && leaf <= inner;
            const double one_slot = as_leaf[i] ? leaf : inner;
            slots_cost(i, 1) = one_slot;
            for (int k = 2; k <= N; ++k) {
                if (one_slot <= best[k]) {
                    slots_cost(i, k) = one_slot;
                    split[std::size_t(i) * N + std::size_t(k - 1)] = 0;
                } else {
                    slots_cost(i, k) = best[k];
                }
            }
        }

        void gather(std::uint32_t i, int k, std::array<std::uint32_t, N>& children, int& child_count) {
            const std::uint8_t j = k == 1 ? 0 : split[std::size_t(i) * N + std::size_t(k - 1)];
            if (binary.nodes()[i].is_leaf() || j == 0) {
                children[child_count++] = i;
                return;
            }
            gather(binary.nodes()[i].index, j, children, child_count);
            gather(binary.nodes()[i].index + 1, k - j, children, child_count);
        }

        bool becomes_leaf(std::uint32_t i) const { return as_leaf[i] != 0; }

        // Makes the wide node for binary inner node i; returns its index.
        std::uint32_t collapse(std::uint32_t i) {
            std::array<std::uint32_t, N> children{};
            int child_count = 0;
            const std::uint8_t j = split[std::size_t(i) * N + std::size_t(N - 1)];
            gather(binary.nodes()[i].index, j, children, child_count);
            gather(binary.nodes()[i].index + 1, N - j, children, child_count);
            const std::uint32_t wide = tree.new_node();
            for (int c = 0; c < child_count; ++c) fill_child(wide, c, children[c]);
            return wide;
        }

        void fill_child(std::uint32_t wide, int slot, std::uint32_t i) {
            const Aabb<Real>& box = binary.nodes()[i].bounds;
            for (int axis = 0; axis < 3; ++axis) {
                tree.nodes_[wide].bounds[axis][slot] = box.min[axis];
                tree.nodes_[wide].bounds[3 + axis][slot] = box.max[axis];
            }
            if (becomes_leaf(i)) {
                auto& indices = tree.primitive_indices_;
                const auto& binary_indices = binary.primitive_indices();
                const Range range = ranges[i];
                tree.nodes_[wide].set_leaf(slot, std::uint32_t(indices.size()), range.end - range.begin);
                indices.insert(indices.end(), binary_indices.begin() + range.begin, binary_indices.begin() + range.end);
                while (indices.size() % N != 0) indices.push_back(indices.back());
            } else {
                const std::uint32_t node = collapse(i);  // may reallocate nodes_: index again
                tree.nodes_[wide].set_inner(slot, node);
            }
        }
    };

    std::vector<WideBvhNode<Real, N>> nodes_;
    std::vector<std::uint32_t> primitive_indices_;
    Aabb<Real> bounds_;
};

}  // namespace prism
