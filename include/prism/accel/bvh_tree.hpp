// A binary BVH over bounding boxes, built with binned SAH (Wald 2007, "On fast Construction of
// SAH-based Bounding Volume Hierarchies") in parallel with TBB, and traversed front to back.
// The tree holds no primitives: traversal hands each leaf's range of primitive_indices to a
// callback, so one tree serves triangles of a mesh and instances of a scene alike.
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/geometry/aabb.hpp>
#include <prism/math/floating_point.hpp>
#include <prism/memory/huge_page_allocator.hpp>
#include <prism/simd/prefetch.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <numeric>
#include <span>
#include <type_traits>
#include <vector>

namespace prism {

struct BvhBuildOptions {
    int bin_count = 16;
    std::uint32_t max_leaf_size = 8;
    float traversal_cost = 1.0f;     // relative to one primitive test
    std::uint32_t parallel_threshold = 4096;  // subtrees at least this large build as tasks
    // A node of at most max_leaf_size primitives becomes a leaf whatever SAH says of splitting
    // it. The wide BVH asks for this: it collapses every such subtree into one leaf anyway, so
    // the splits below it were work thrown away (a quarter to a third of the build). The leaf
    // holds the same primitives either way, in the order the parent's partition left them.
    bool leaf_at_max_size = false;
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
        return build(static_cast<std::uint32_t>(boxes.size()), [boxes](std::uint32_t i) { return boxes[i]; }, options);
    }

    // The same from `box_of(i)`, the box of primitive i, asked once per primitive: a caller
    // that makes its boxes (a mesh from its triangles) hands them straight to the builder's own
    // array instead of filling one of its own first (on the 766k-triangle dragon an 18 MB array
    // written, faulted in and read back once). Below 2 setup_grain primitives it is asked in
    // order on one thread; above, from every thread at once, in runs.
    template <class BoxOf>
        requires std::is_invocable_r_v<Aabb<Real>, const BoxOf&, std::uint32_t>
    static BvhTree build(std::uint32_t count, const BoxOf& box_of, const BvhBuildOptions& options = {}) {
        BvhTree tree;
        tree.primitive_indices_.resize(count);
        std::iota(tree.primitive_indices_.begin(), tree.primitive_indices_.end(), 0u);
        if (count == 0) return tree;
        // The builder's arrays are written whole before they are read, so they are not cleared,
        // and come in huge pages: fresh memory's page faults in 4 kB pages were a tenth of the
        // dragon's build.
        HugePageVector<BuildBox> build_boxes(count);
        // The boxes are made in parallel, each task bounding its own run of primitives; the
        // runs' bounds are joined in the runs' order. Aabb::extend keeps the earlier of two
        // equal values (and never takes a NaN), so this finds the same bits, the sign of a zero
        // included, as one loop from the first primitive to the last.
        struct Bounds {
            Aabb<Real> boxes, centroids;
        };
        const auto make_boxes = [&](const tbb::blocked_range<std::uint32_t>& run, Bounds bounds) {
            for (std::uint32_t i = run.begin(); i < run.end(); ++i) {
                const Aabb<Real> box = box_of(i);
                build_boxes[i] = BuildBox::of(box);
                bounds.boxes.extend(box);
                bounds.centroids.extend(box.centroid());
            }
            return bounds;
        };
        const auto join = [](Bounds earlier, const Bounds& later) {
            earlier.boxes.extend(later.boxes);
            earlier.centroids.extend(later.centroids);
            return earlier;
        };
        const Bounds bounds =
            count >= 2 * setup_grain
                ? tbb::parallel_reduce(tbb::blocked_range<std::uint32_t>(0, count, setup_grain), Bounds{}, make_boxes, join)
                : make_boxes(tbb::blocked_range<std::uint32_t>(0, count), Bounds{});
        const Aabb<Real> &root_bounds = bounds.boxes, &centroid_bounds = bounds.centroids;
        // A tree has at most 2 count - 1 nodes, but leaves of several primitives make far fewer.
        // The builder writes into storage of the bound left uninitialised, and only the nodes
        // made are copied out: the pages of the unused part are never touched (initialising
        // them, and copying to shrink afterwards, cost a tenth of the dragon's build in page
        // faults). Every node is written before it is read; the storage of an allocation
        // function holds BvhNodes (an aggregate) as soon as they are written (C++20 implicit
        // object creation).
        const std::size_t capacity = 2 * std::size_t(count) - 1;
        const auto release = [capacity](BvhNode<Real>* nodes) { HugePageAllocator<BvhNode<Real>>().deallocate(nodes, capacity); };
        const std::unique_ptr<BvhNode<Real>[], decltype(release)> storage(HugePageAllocator<BvhNode<Real>>().allocate(capacity),
                                                                        release);
        BvhNode<Real>* const nodes = storage.get();
        nodes[0] = {root_bounds, 0, 0};
        // The large nodes' partition scratch, one byte and one index per primitive, made once:
        // a node uses the slots of its own range, which no node being partitioned at the same
        // time shares (a parallel subtree starts after its parent's partition has ended).
        HugePageVector<std::uint8_t> sides(count > Builder::scratch_on_stack ? count : 0);
        HugePageVector<std::uint32_t> moves(sides.size());
        Builder builder{build_boxes.data(), tree.primitive_indices_, nodes, options, {1}, sides.data(), moves.data()};
        builder.build(0, 0, count, centroid_bounds, 0);
        tree.nodes_.assign(nodes, nodes + builder.node_count.load());
        return tree;
    }

    const std::vector<BvhNode<Real>>& nodes() const { return nodes_; }
    const std::vector<std::uint32_t>& primitive_indices() const { return primitive_indices_; }
    Aabb<Real> bounds() const { return nodes_.empty() ? Aabb<Real>{} : nodes_[0].bounds; }
    int depth() const { return nodes_.empty() ? 0 : depth_of(0); }
    std::size_t memory_bytes() const {
        return nodes_.capacity() * sizeof(BvhNode<Real>) + primitive_indices_.capacity() * sizeof(std::uint32_t);
    }

    // Closest hit: `leaf(first, count, t_max)` tests primitive_indices[first, first + count),
    // lowering t_max on hits. Children are visited nearest first so t_max prunes early.
    template <class Leaf>
    void traverse_closest(const Ray<Real>& ray, Real& t_max, Leaf&& leaf) const {
        traverse<false>(TraversalRay(ray), ray.t_min, t_max, leaf);
    }

    // Any hit: stops as soon as `leaf(first, count, t_max)` returns true.
    template <class Leaf>
    bool traverse_any(const Ray<Real>& ray, Real t_max, Leaf&& leaf) const {
        return traverse<true>(TraversalRay(ray), ray.t_min, t_max, leaf);
    }

    // The same from a ray prepared once (shared by both levels of a scene, as in WideBvhTree).
    using TraversalRay = RayBoxPrecomputed<Real>;
    template <class Leaf>
    void traverse_closest(const TraversalRay& ray, Real t_min, Real& t_max, Leaf&& leaf) const {
        traverse<false>(ray, t_min, t_max, leaf);
    }
    template <class Leaf>
    bool traverse_any(const TraversalRay& ray, Real t_min, Real t_max, Leaf&& leaf) const {
        return traverse<true>(ray, t_min, t_max, leaf);
    }

private:
    static constexpr Real far_scale = robust_far_scale<Real>;  // geometry/aabb.hpp
    // Primitives per task where the builder's per-primitive passes run in parallel: below two
    // of these, one thread (a task costs more than it saves).
    static constexpr std::uint32_t setup_grain = 16384;

    static Real enter(const BvhNode<Real>& node, const RayBoxPrecomputed<Real>& ray, Real t_min, Real t_max) {
        return intersect_box(node.bounds, ray, t_min, t_max * far_scale, far_scale);
    }

    template <bool AnyHit, class Leaf>
    bool traverse(const TraversalRay& box_ray, Real t_min, Real& t_max, Leaf& leaf) const {
        if (nodes_.empty()) return false;
        if (enter(nodes_[0], box_ray, t_min, t_max) == infinity<Real>) return false;
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
                const Real t_left = enter(nodes_[left], box_ray, t_min, t_max);
                const Real t_right = enter(nodes_[right], box_ray, t_min, t_max);
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

    // Four lanes of Real, the builder's unit of work: a box corner (x, y, z and an unused
    // fourth lane) or a centroid. Under GCC and Clang a vector type, whose `a < b ? a : b` is
    // one SSE/AVX minimum with IEEE semantics (x86's minps returns its second operand on NaN or
    // equality, as the ternary does), so every lane keeps the scalar expression's bits. Not
    // simd::Pack: its select became an AVX-512 masked store into the bin, and a masked store
    // cannot forward to the next load of that bin, which stalled every bin update. Values of
    // this type are passed by reference only: returning a 32-byte vector by value warns
    // (-Wpsabi) where AVX is not enabled.
#if defined(__GNUC__) || defined(__clang__)
    typedef Real Lanes __attribute__((vector_size(4 * sizeof(Real))));
    typedef int Bins __attribute__((vector_size(4 * sizeof(int))));
    static void keep_min(Lanes& into, const Lanes& x) { into = x < into ? x : into; }
    static void keep_max(Lanes& into, const Lanes& x) { into = into < x ? x : into; }
    static void half_sum(const Lanes& a, const Lanes& b, Lanes& out) { out = (a + b) * Real(0.5); }
    static void shift_scale(const Lanes& x, const Lanes& shift, const Lanes& scale, Lanes& out) {
        out = (x - shift) * scale;
    }
    // int(position) lane by lane, clamped to [0, last]: one truncating conversion (cvttps2dq,
    // or cvttpd2dq for double) and two integer clamps for the three axes, where the scalar form
    // took three conversions and six clamps. x86 converts NaN and out-of-range values to
    // INT_MIN in both forms, which the clamp sends to bin 0.
    static void bins_at(const Lanes& position, int last, Bins& out) {
        out = __builtin_convertvector(position, Bins);
        out = out < last ? out : last;
        out = out > 0 ? out : 0;
    }
#else
    using Lanes = std::array<Real, 4>;
    static void keep_min(Lanes& into, const Lanes& x) {
        for (int k = 0; k < 4; ++k) into[k] = x[k] < into[k] ? x[k] : into[k];
    }
    static void keep_max(Lanes& into, const Lanes& x) {
        for (int k = 0; k < 4; ++k) into[k] = into[k] < x[k] ? x[k] : into[k];
    }
    static void half_sum(const Lanes& a, const Lanes& b, Lanes& out) {
        for (int k = 0; k < 4; ++k) out[k] = (a[k] + b[k]) * Real(0.5);
    }
    static void shift_scale(const Lanes& x, const Lanes& shift, const Lanes& scale, Lanes& out) {
        for (int k = 0; k < 4; ++k) out[k] = (x[k] - shift[k]) * scale[k];
    }
    using Bins = std::array<int, 4>;
    static void bins_at(const Lanes& position, int last, Bins& out) {
        for (int k = 0; k < 4; ++k) out[k] = int(position[k]);
        for (int k = 0; k < 4; ++k) out[k] = out[k] < last ? out[k] : last;
        for (int k = 0; k < 4; ++k) out[k] = out[k] > 0 ? out[k] : 0;
    }
#endif

    // A box as the builder reads it: four lanes per corner, contiguous and in the order of
    // primitive_indices, so every pass over a node reads one range instead of gathering boxes
    // through the indices (a cache miss per primitive per level once the partitions have
    // scrambled the order), and each corner's minimum or maximum is one 4-wide operation. The
    // partitions permute boxes and indices together.
    struct BuildBox {
        Lanes min, max;

        static BuildBox of(const Aabb<Real>& box) {
            BuildBox made;
            for (int axis = 0; axis < 3; ++axis) {
                made.min[axis] = box.min[axis];
                made.max[axis] = box.max[axis];
            }
            made.min[3] = made.max[3] = Real(0);
            return made;
        }
        Aabb<Real> aabb() const { return {{min[0], min[1], min[2]}, {max[0], max[1], max[2]}}; }
        // Each lane's (min + max) * 0.5, as Aabb::centroid computes it, so bins and partitions
        // see the same centroids.
        PRISM_FORCE_INLINE void centroid(Lanes& out) const { half_sum(min, max, out); }
        // glm::min(min, other.min) and glm::max, lane by lane in the same operand order.
        PRISM_FORCE_INLINE void extend(const BuildBox& other) {
            keep_min(min, other.min);
            keep_max(max, other.max);
        }
        // glm::min(min, point), as Aabb::extend(point) takes it.
        PRISM_FORCE_INLINE void extend(const Lanes& point) {
            keep_min(min, point);
            keep_max(max, point);
        }
        // Aabb::half_area's operations in its order, so the SAH costs keep their bits.
        Real half_area() const {
            if (min[0] > max[0] || min[1] > max[1] || min[2] > max[2]) return 0;
            const Real x = max[0] - min[0], y = max[1] - min[1], z = max[2] - min[2];
            return x * y + y * z + z * x;
        }
        // Written as constants: filled lane by lane, GCC rebuilt the two vectors with four
        // inserts each for every bin a node resets (6% of the builder's time on the dragon).
        static BuildBox empty() {
            constexpr Real high = infinity<Real>;
            BuildBox made;
            made.min = Lanes{high, high, high, high};
            made.max = Lanes{-high, -high, -high, -high};
            return made;
        }
    };

    struct Builder {
        BuildBox* boxes;  // in the order of indices
        std::vector<std::uint32_t>& indices;
        BvhNode<Real>* nodes;  // room for 2 count - 1
        const BvhBuildOptions& options;
        std::atomic<std::uint32_t> node_count;
        std::uint8_t* shared_sides;     // the partition's scratch for nodes too large for the stack
        std::uint32_t* shared_moves;  // (count slots each: see partition)
        static constexpr std::uint32_t scratch_on_stack = 1024;

        static constexpr int max_bins = 64;
        // Below this many primitives one set of bins is used (resetting and merging a second
        // costs more than the stalls it saves).
        static constexpr std::uint32_t two_bin_sets_from = 64;

        struct BinSet {
            std::array<std::array<BuildBox, max_bins>, 3> bounds;
            std::array<std::array<std::uint32_t, max_bins>, 3> counts;
            std::array<std::uint64_t, 3> occupied;  // bit b: bin b holds a primitive

            void reset(int bin_count) {
                for (int axis = 0; axis < 3; ++axis) {
                    for (int b = 0; b < bin_count; ++b) {
                        bounds[axis][b] = BuildBox::empty();
                        counts[axis][b] = 0;
                    }
                    occupied[axis] = 0;
                }
            }
            // Inlined by force: GCC kept it a call, and the box then went through the stack.
            // Without MarkOccupied, `occupied` is left for merge to find from the counts: in a
            // large node that is a few dozen tests per node instead of three per primitive.
            template <bool MarkOccupied = true>
            PRISM_FORCE_INLINE void add(const BuildBox& box, const Bins& bin) {
                for (int axis = 0; axis < 3; ++axis) {
                    bounds[axis][bin[axis]].extend(box);
                    ++counts[axis][bin[axis]];
                    if constexpr (MarkOccupied) occupied[axis] |= std::uint64_t(1) << bin[axis];
                }
            }
            // Adds other's bins to these, and marks the bins that hold a primitive.
            void merge(const BinSet& other, int bin_count) {
                for (int axis = 0; axis < 3; ++axis) {
                    std::uint64_t mask = 0;
                    for (int b = 0; b < bin_count; ++b) {
                        bounds[axis][b].extend(other.bounds[axis][b]);
                        counts[axis][b] += other.counts[axis][b];
                        mask |= std::uint64_t(counts[axis][b] != 0) << b;
                    }
                    occupied[axis] = mask;
                }
            }
        };

        void make_leaf(std::uint32_t node, std::uint32_t begin, std::uint32_t end) {
            nodes[node].index = begin;
            nodes[node].count = end - begin;
        }

        // `centroid_bounds` bounds the centroids of the primitives in [begin, end): the
        // parent's partition measured it, which saves a pass over the range per node.
        void build(std::uint32_t node, std::uint32_t begin, std::uint32_t end, const Aabb<Real>& centroid_bounds,
                   int depth) {
            const std::uint32_t count = end - begin;
            // Leave room on the traversal stack: past max_depth - 1, stop splitting.
            if (count <= 1 || depth >= max_depth - 2) return make_leaf(node, begin, end);
            if (options.leaf_at_max_size && count <= options.max_leaf_size) return make_leaf(node, begin, end);
            const BuildBox* const range = boxes + begin;

            const int bin_count = std::min(options.bin_count, max_bins);
            std::array<bool, 3> splittable{};
            std::array<Real, 4> low{}, scale{};  // four lanes, as the boxes
            for (int axis = 0; axis < 3; ++axis) {
                splittable[axis] = centroid_bounds.max[axis] > centroid_bounds.min[axis];
                low[axis] = centroid_bounds.min[axis];
                if (splittable[axis])
                    scale[axis] = Real(bin_count) / (centroid_bounds.max[axis] - centroid_bounds.min[axis]);
            }
            Lanes low_lanes, scale_lanes;
            for (int k = 0; k < 4; ++k) {
                low_lanes[k] = low[k];
                scale_lanes[k] = scale[k];
            }
            // Where a box's centroid falls, in bins, on every axis at once: the scalar
            // (centroid - low) * scale in its order, lane by lane (one SIMD operation a step).
            const auto bin_positions = [&](const Lanes& centroid, Lanes& position) PRISM_FORCE_INLINE {
                shift_scale(centroid, low_lanes, scale_lanes, position);
            };
            // The bins, lane by lane. An axis that cannot be split puts everything in bin 0; so
            // does a NaN centroid (an empty box, e.g. an instance of an empty mesh), which
            // converts to INT_MIN on x86.
            const auto bins_of = [&](const BuildBox& box) PRISM_FORCE_INLINE {
                Lanes centroid, position;
                box.centroid(centroid);
                bin_positions(centroid, position);
                Bins bin;
                bins_at(position, bin_count - 1, bin);
                return bin;
            };

            // All three axes are binned in one pass over the range (one read of each box, not
            // three). In large nodes even and odd primitives go to separate sets of bins, merged
            // afterwards: neighbours often fall in the same bin, and with one set each update
            // waits for the previous one's store. Minimum, maximum and count do not depend on
            // the order, so the bins (and the tree) are the same.
            BinSet bins, odd_bins;
            bins.reset(bin_count);
            if (count >= two_bin_sets_from) {
                odd_bins.reset(bin_count);
                std::uint32_t i = 0;
                for (; i + 1 < count; i += 2) {
                    // As in the partition: the largest nodes stream their boxes from memory,
                    // and the box loads were this loop's hottest instructions.
                    simd::prefetch(range[std::min(i + 16, count - 1)]);
                    bins.template add<false>(range[i], bins_of(range[i]));
                    odd_bins.template add<false>(range[i + 1], bins_of(range[i + 1]));
                }
                if (i < count) bins.template add<false>(range[i], bins_of(range[i]));
                bins.merge(odd_bins, bin_count);
            } else {
                for (std::uint32_t i = 0; i < count; ++i) bins.add(range[i], bins_of(range[i]));
            }

            int best_axis = -1, best_split = 0;
            Real best_cost = infinity<Real>;
            Aabb<Real> best_left, best_right;
            for (int axis = 0; axis < 3; ++axis) {
                if (!splittable[axis]) continue;
                // Sweep from the right, then from the left, over the bins that hold primitives.
                // A plane after an empty bin splits the primitives as the plane before that bin
                // does, at the same cost, so the strict `cost < best_cost` never takes it: only
                // the planes just after a filled bin are evaluated, which in the many small
                // nodes near the leaves (a handful of primitives in 16 bins) saves most of the
                // sweep. The boxes are extended in the same order as a sweep over every bin
                // (empty bins change nothing), so the costs, and the tree, keep their bits.
                std::array<int, max_bins> filled;
                int filled_count = 0;
                for (std::uint64_t mask = bins.occupied[axis]; mask != 0; mask &= mask - 1)
                    filled[filled_count++] = std::countr_zero(mask);
                // right_bounds[j] bounds the filled bins j, j + 1, ...; right_cost[j] is its SAH term.
                std::array<Real, max_bins> right_cost;
                std::array<BuildBox, max_bins> right_bounds;
                BuildBox accumulated = BuildBox::empty();
                std::uint32_t accumulated_count = 0;
                for (int j = filled_count - 1; j > 0; --j) {
                    accumulated.extend(bins.bounds[axis][filled[j]]);
                    accumulated_count += bins.counts[axis][filled[j]];
                    right_bounds[j] = accumulated;
                    right_cost[j] = accumulated.half_area() * Real(accumulated_count);
                }
                accumulated = BuildBox::empty();
                accumulated_count = 0;
                for (int j = 0; j + 1 < filled_count; ++j) {
                    accumulated.extend(bins.bounds[axis][filled[j]]);
                    accumulated_count += bins.counts[axis][filled[j]];
                    const Real cost = accumulated.half_area() * Real(accumulated_count) + right_cost[j + 1];
                    if (cost < best_cost) {
                        best_cost = cost;
                        best_axis = axis;
                        best_split = filled[j] + 1;
                        best_left = accumulated.aabb();
                        best_right = right_bounds[j + 1].aabb();
                    }
                }
            }

            const Real node_area = nodes[node].bounds.half_area();
            const Real leaf_cost = Real(count);
            const Real split_cost =
                Real(options.traversal_cost) + (node_area > 0 ? best_cost / node_area : Real(count));
            std::uint32_t middle;
            Aabb<Real> left_centroids, right_centroids;
            if (best_axis < 0) {
                // All centroids coincide: SAH cannot separate them; split by count if too many.
                if (count <= options.max_leaf_size) return make_leaf(node, begin, end);
                middle = begin + count / 2;
                best_left = {};
                best_right = {};
                for (std::uint32_t i = begin; i < middle; ++i) best_left.extend(boxes[i].aabb());
                for (std::uint32_t i = middle; i < end; ++i) best_right.extend(boxes[i].aabb());
                left_centroids = right_centroids = centroid_bounds;  // all the same point
            } else {
                if (count <= options.max_leaf_size && leaf_cost <= split_cost) return make_leaf(node, begin, end);
                // The children's centroid bounds, gathered lane by lane as the partition sees
                // each box (the same minima and maxima Aabb::extend would find), indexed by
                // side rather than chosen by a branch the data would mispredict. Even and odd
                // primitives keep separate bounds, merged afterwards, as the bins do: with one
                // pair, a run of primitives on one side waited for each other's store (the
                // loop's hottest instruction on the dragon). The lanes that matter take the same
                // values in either order; only the sign of a zero bound may differ, and
                // (c - low) * scale bins a centroid the same for +0 and -0.
                std::array<BuildBox, 4> centroid_lanes;  // [2 * odd + left]
                centroid_lanes.fill(BuildBox::empty());
                const auto goes_left = [&](const BuildBox& box, std::uint32_t odd) PRISM_FORCE_INLINE {
                    Lanes centroid, position;
                    box.centroid(centroid);
                    bin_positions(centroid, position);
                    const bool left = std::min(bin_count - 1, int(position[best_axis])) < best_split;
                    centroid_lanes[2 * odd + left].extend(centroid);
                    return left;
                };
                middle = begin + partition(begin, end, goes_left);
                centroid_lanes[0].extend(centroid_lanes[2]);
                centroid_lanes[1].extend(centroid_lanes[3]);
                left_centroids = centroid_lanes[1].aabb();
                right_centroids = centroid_lanes[0].aabb();
            }

            const std::uint32_t left = node_count.fetch_add(2);
            nodes[node].index = left;
            nodes[node].count = 0;
            nodes[left] = {best_left, 0, 0};
            nodes[left + 1] = {best_right, 0, 0};
            if (count >= options.parallel_threshold) {
                tbb::parallel_invoke([&] { build(left, begin, middle, left_centroids, depth + 1); },
                                     [&] { build(left + 1, middle, end, right_centroids, depth + 1); });
            } else {
                build(left, begin, middle, left_centroids, depth + 1);
                build(left + 1, middle, end, right_centroids, depth + 1);
            }
        }

        // Moves the primitives of [begin, end) for which goes_left holds to the front, boxes and
        // indices together, and returns how many there are; goes_left(box, odd) sees each primitive
        // once, odd telling the parity of its place (for the caller's two sets of bounds).
        // The swaps are those of libstdc++'s std::partition, which this builder used before, so
        // the primitive order is unchanged. Hoare's scheme from both ends swaps the k-th
        // primitive from the front that goes right with the k-th from the back that goes left,
        // until the two meet where the left ones end. Written as that scan, it takes a branch
        // per primitive that the data mispredicts half the time; here the same pairs are found
        // in branch-free passes: each primitive's side, then the misplaced ones of each part.
        template <class GoesLeft>
        std::uint32_t partition(std::uint32_t begin, std::uint32_t end, const GoesLeft& goes_left) {
            const std::uint32_t count = end - begin;
            // moves takes at most count slots: the front pass writes slot misplaced <= i below
            // left_count, the back pass slots misplaced + found, where misplaced (right-goers
            // among the first left_count) <= left_count and found < count - left_count.
            std::array<std::uint8_t, scratch_on_stack> stack_sides;
            std::array<std::uint32_t, scratch_on_stack> stack_moves;
            std::uint8_t* sides = stack_sides.data();
            std::uint32_t* moves = stack_moves.data();
            if (count > scratch_on_stack) {
                sides = shared_sides + begin;
                moves = shared_moves + begin;
            }
            // In a local: a store to sides (bytes, which may alias anything) made the compiler
            // reload the member before every box.
            BuildBox* const range = boxes + begin;
            std::uint32_t left_count = 0;
            for (std::uint32_t i = 0; i < count; ++i) {
                // Large nodes stream their boxes from memory, and this loop's chain of side-indexed
                // updates leaves the hardware prefetcher behind: ask half a kilobyte ahead.
                simd::prefetch(range[std::min(i + 16, count - 1)]);
                const bool left = goes_left(range[i], i & 1u);
                sides[i] = left;
                left_count += left;
            }
            // Right-goers in the front part, first to last; then left-goers in the back part,
            // last to first. There are as many of each; every slot is written, kept or not.
            std::uint32_t misplaced = 0;
            for (std::uint32_t i = 0; i < left_count; ++i) {
                moves[misplaced] = i;
                misplaced += sides[i] ^ 1u;
            }
            std::uint32_t* const from_back = moves + misplaced;
            std::uint32_t found = 0;
            for (std::uint32_t i = count; i-- > left_count;) {
                from_back[found] = i;
                found += sides[i];
            }
            for (std::uint32_t k = 0; k < misplaced; ++k) {
                std::swap(range[moves[k]], range[from_back[k]]);
                std::swap(indices[begin + moves[k]], indices[begin + from_back[k]]);
            }
            return left_count;
        }
    };

    std::vector<BvhNode<Real>> nodes_;
    std::vector<std::uint32_t> primitive_indices_;
};

}  // namespace prism
