// How WideBvhTree::build (accel/wide_bvh_tree.hpp) makes wide nodes of the binned-SAH binary
// tree (accel/bvh_tree.hpp), by the surface area heuristic: for every binary subtree, the cheapest
// way to spread it over 1..N child slots is found bottom up (dynamic programming, as Ylitie,
// Karras and Laine 2017 collapse into their compressed wide BVH), and each wide node takes the
// cheapest spread of its binary node's two subtrees over all N slots. Opening the largest-area
// child until N children are found (Wald, Benthin, Boulos 2008) had left 4.3 children per node
// on the tiny-triangle dragon; this collapse gives 7.4 and 8-10% faster rays (bench/RESULTS.md).
// Included by wide_bvh_tree.hpp, after the class: this is its nested Collapser.
#pragma once

#include <prism/accel/bvh_tree.hpp>
#include <prism/accel/wide_bvh_tree.hpp>
#include <prism/memory/huge_page_allocator.hpp>

#include <tbb/parallel_invoke.h>

#include <array>
#include <cstddef>
#include <cstdint>

namespace prism {

template <Scalar Real, int N>
struct WideBvhTree<Real, N>::Collapser {
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

}  // namespace prism
