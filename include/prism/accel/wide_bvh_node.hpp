// A node of the wide BVH (accel/wide_bvh_tree.hpp): up to N children (4 or 8) whose boxes are
// stored SoA, so that one SIMD slab test decides them all, and each child in one tagged word
// that tells an inner node from a leaf.
#pragma once

#include <prism/math/vector.hpp>

#include <cstdint>
#include <stdexcept>

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

}  // namespace prism
