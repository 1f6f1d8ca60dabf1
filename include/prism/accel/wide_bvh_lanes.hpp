// WideBvhTree's traversals of several rays at once (accel/wide_bvh_tree.hpp): a ray is tested
// at a node only if it entered that node's box, by its own slab set-up and the node test the
// one-ray traversal makes, while the node tests of the rays that reach a node overlap.
// Included by wide_bvh_tree.hpp, after the class: these are its members' definitions, declared
// inline as they were when written in the class, so that the compiler inlines them as before.
#pragma once

#include <prism/accel/wide_bvh_tree.hpp>
#include <prism/simd/pack.hpp>
#include <prism/simd/prefetch.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>

namespace prism {

// Any hit for several rays at once (bit i of `lanes` for ray i, i < 32: a row's shadow rays
// to one light), each ray's answer traverse_any's: a ray is tested at a node only if it
// entered that node's box, with its own slab set-up (`slabs[i]`) and the node test
// traverse_any makes, so each ray reaches exactly the leaves it would reach alone. Only the
// order of the visits differs, which an any-hit answer does not depend on.
// leaf(first, count, lanes) tests the leaf's primitives for the rays of `lanes` and returns
// the blocked ones; the answer is every blocked ray.
// The rays' node tests are independent of each other: where one ray waits on each node's
// test before it can load the next node, the tests of the rays that reach a node overlap.
template <Scalar Real, int N>
template <class Leaf>
inline std::uint32_t WideBvhTree<Real, N>::traverse_any_lanes(const TraversalRay* slabs, const Real* t_min, const Real* t_max,
                                                              std::uint32_t lanes, Leaf&& leaf) const {
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
template <Scalar Real, int N>
template <class Leaf>
inline std::uint32_t WideBvhTree<Real, N>::traverse_closest_lanes(const TraversalRay* slabs, const Real* t_min, Real* t_max,
                                                                  std::uint32_t lanes, Leaf&& leaf) const {
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
template <Scalar Real, int N>
template <class Each>
inline std::array<std::uint32_t, N> WideBvhTree<Real, N>::children_entered(const WideBvhNode<Real, N>& node,
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
template <Scalar Real, int N>
constexpr std::uint64_t WideBvhTree<Real, N>::transpose_bits(std::uint64_t x) {
    std::uint64_t t = (x ^ (x >> 7)) & 0x00AA00AA00AA00AAull;
    x ^= t ^ (t << 7);
    t = (x ^ (x >> 14)) & 0x0000CCCC0000CCCCull;
    x ^= t ^ (t << 14);
    t = (x ^ (x >> 28)) & 0x00000000F0F0F0F0ull;
    x ^= t ^ (t << 28);
    return x;
}

}  // namespace prism
