// The index over a triangle mesh in its object space: the bottom level of the two-level
// hierarchy, shared by every object that places the mesh. Triangles are stored as a vertex soup
// in index order (or as packets of the wide BVH's leaves), so a leaf reads contiguous memory.
// SceneIndex also builds one over several meshes in world space (one index for all their
// triangles). What a hit means (normals, texture coordinates) is MeshSurface's
// (geometry/mesh_surface.hpp), which keeps the triangles in the same slot order.
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/accel/accelerator.hpp>
#include <prism/geometry/hit.hpp>
#include <prism/geometry/surface_error.hpp>
#include <prism/geometry/triangle_packets.hpp>
#include <prism/math/floating_point.hpp>
#include <prism/memory/huge_page_allocator.hpp>
#include <prism/parallel/for_each_run.hpp>
#include <prism/scene/scene.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <type_traits>
#include <vector>

namespace prism {

template <Scalar Real, class Policy>
    requires AccelerationPolicy<Policy, Real>
class TriangleMesh {
public:
    using Intersector = typename Policy::Intersector;
    using Storage = typename Intersector::template Storage<Real>;
    using Index = typename Policy::template Index<Real>;
    using Prepared = typename Intersector::template Prepared<Real>;
    using Packets = typename TrianglePacketsOf<Policy, Real>::type;
    static constexpr bool packed = !std::is_same_v<Packets, NoTrianglePackets>;

    // `max_leaf_size` bounds the index's leaves (BvhBuildOptions::max_leaf_size); 0 leaves them
    // to the index's own default and its surface area heuristic (an index without leaves, the
    // brute-force list, has nothing to bound).
    explicit TriangleMesh(const scene::Mesh& mesh, std::uint32_t max_leaf_size = 0) {
        const scene::Mesh* const parts[] = {&mesh};
        build(parts, max_leaf_size);
    }

    // One index over the triangles of several meshes that share a space, numbered part after
    // part (part 0's triangles first). A hit's slot names its triangle through source_triangle.
    explicit TriangleMesh(std::span<const scene::Mesh* const> parts, std::uint32_t max_leaf_size = 0) {
        build(parts, max_leaf_size);
    }

    // The box of a mesh's triangles, as an index over them would bound them (each triangle's
    // box widened where Storage is wider than Real), without building the index.
    static Aabb<Real> bounds_of(const scene::Mesh& mesh) {
        Aabb<Real> box;
        for (const auto& face : mesh.triangles) box.extend(triangle_box(mesh, face));
        return box;
    }

    // The slots' triangles as the file numbers them: what MeshSurface keeps in the same order.
    std::span<const std::uint32_t> slot_order() const { return index_.primitive_indices(); }

    // The triangle in `slot`, numbered as the meshes it was built from list them (part after
    // part for several meshes).
    std::uint32_t source_triangle(std::uint32_t slot) const {
        if constexpr (packed) {
            if constexpr (Packets::keeps_sources) return packets_.source(slot);
        }
        return index_.primitive_indices()[slot];
    }

    Aabb<Real> bounds() const { return bounds_; }
    std::size_t triangle_count() const { return triangle_count_; }
    // What traversal reads: the index and the triangles its leaves test.
    std::size_t accelerator_bytes() const {
        std::size_t bytes = index_.memory_bytes() + triangles_.capacity() * sizeof(triangles_[0]);
        if constexpr (packed) bytes += packets_.memory_bytes();
        return bytes;
    }

    using TraversalRay = typename Index::TraversalRay;
    // What the triangle tests need of a ray, computed once per ray: the watertight shear, and
    // its broadcast into packets under a wide BVH.
    struct TriangleRay {
        Prepared prepared;
        typename Packets::PackedRay packed_ray;
        explicit TriangleRay(const Ray<Real>& ray) : prepared(ray), packed_ray(prepared) {}
    };

    // Whether a ray may reach a leaf of the index, decided by the index's own first node test
    // (WideBvhTree::enters); only for an index that has one.
    PRISM_FORCE_INLINE bool enters(const TraversalRay& ray, Real t_min, Real t_max) const
        requires requires(const Index& index) { index.enters(ray, t_min, t_max); }
    {
        return index_.enters(ray, t_min, t_max);
    }

    // The slots [first, first + count) of the one leaf that holds every triangle, when the
    // index is a single leaf (a wide BVH over at most N triangles: a root with one child).
    // SceneIndex tests such a mesh's leaf directly (intersect_leaf, occluded_leaf), without
    // the traversal ray or the root's box test that would only lead to it.
    struct Leaf {
        std::uint32_t first = 0, count = 0;
        Aabb<Real> box;  // the box the root's test would test (its one child's)
    };
    std::optional<Leaf> single_leaf() const {
        const std::optional<RootLeaves> leaves = root_leaves();
        if (leaves && leaves->count == 1) return leaves->leaf[0];
        return std::nullopt;
    }

    // The leaves of an index whose root holds nothing but leaves, at most max_root_leaves of
    // them (a wide BVH over 9 to 4N triangles: hw1 ocornellbox's ten wall triangles, which the
    // build splits in two; the hw7 Cornell boxes' walls and light, in three), in the root's slot
    // order; none for a larger index.
    static constexpr int max_root_leaves = 4;
    struct RootLeaves {
        std::array<Leaf, max_root_leaves> leaf{};
        int count = 0;
        // The leaves' boxes by axis, a leaf in each lane (lanes past count: empty boxes at 0).
        alignas(4 * sizeof(Real)) Real lower[3][max_root_leaves]{};
        alignas(4 * sizeof(Real)) Real upper[3][max_root_leaves]{};

        // Bit i set where the ray leaves leaf i's box as leaves_box says (the same comparisons,
        // every leaf in one pass): a wall's rays that start beyond it and do not come back, which
        // its leaf's test then skips. Box by box, these tests were a sixth of the hw7 Cornell
        // boxes' traversal instructions (valgrind's count, path_diffuse).
        PRISM_FORCE_INLINE std::uint32_t left_by(const Ray<Real>& ray) const {
            using Lanes = simd::Pack<Real, max_root_leaves>;
            const Lanes zero = Lanes::broadcast(Real(0));
            simd::Mask<Real, max_root_leaves> away = zero < zero;
            for (int axis = 0; axis < 3; ++axis) {
                const Lanes origin = Lanes::broadcast(ray.origin[axis]);
                const Lanes direction = Lanes::broadcast(ray.direction[axis]);
                away = away | ((origin > Lanes::load(upper[axis])) & (direction >= zero)) |
                       ((origin < Lanes::load(lower[axis])) & (direction <= zero));
            }
            return ray.t_min >= 0 ? away.bits() & ((1u << count) - 1) : 0u;
        }
    };
    std::optional<RootLeaves> root_leaves() const {
        if constexpr (packed && requires { Index::width; }) {
            const auto& nodes = index_.nodes();
            if (nodes.size() != 1) return std::nullopt;
            RootLeaves leaves;
            for (int i = 0; i < Index::width; ++i) {
                if (nodes[0].count(i) == 0) continue;
                if (leaves.count == max_root_leaves) return std::nullopt;
                Leaf& leaf = leaves.leaf[std::size_t(leaves.count++)];
                leaf.first = nodes[0].index(i);
                leaf.count = nodes[0].count(i);
                for (int axis = 0; axis < 3; ++axis) {
                    leaf.box.min[axis] = nodes[0].bounds[axis][i];
                    leaf.box.max[axis] = nodes[0].bounds[3 + axis][i];
                    leaves.lower[axis][leaves.count - 1] = leaf.box.min[axis];
                    leaves.upper[axis][leaves.count - 1] = leaf.box.max[axis];
                }
            }
            if (leaves.count > 0) return leaves;
        }
        return std::nullopt;
    }

    // The leaf's test itself, as traversal calls it on that leaf: the same packets, slots and
    // order, so the same hit (closest in (ray.t_min, t_max], later ties winning; t_max lowered)
    // and the same any-hit answer (open at t_max).
    PRISM_FORCE_INLINE bool intersect_leaf(const Ray<Real>& ray, const TriangleRay& triangle_ray, Leaf leaf, Real& t_max,
                                               Hit<Real>& hit, bool cull_back_faces) const
        requires packed
    {
        return packets_.intersect(triangle_ray.packed_ray, ray.direction, leaf.first, leaf.count, ray.t_min, t_max, hit,
                                  cull_back_faces);
    }
    // The same leaf against several rays, one in each lane (TrianglePackets::intersect_lanes):
    // each lane's hit is the one intersect_leaf gives its ray.
    template <class RayLanes, class LaneHits>
    PRISM_FORCE_INLINE void intersect_leaf_lanes(const RayLanes& rays, Leaf leaf, std::uint32_t lanes, LaneHits& hits,
                                                     bool cull_back_faces) const
        requires packed
    {
        packets_.intersect_lanes(rays, leaf.first, leaf.count, lanes, hits, cull_back_faces);
    }
    template <class RayLanes, class LanePack>
    PRISM_FORCE_INLINE std::uint32_t occluded_leaf_lanes(const RayLanes& rays, Leaf leaf, std::uint32_t lanes,
                                                             const LanePack& t_max) const
        requires packed
    {
        return packets_.occluded_lanes(rays, leaf.first, leaf.count, lanes, t_max);
    }
    PRISM_FORCE_INLINE bool occluded_leaf(const Ray<Real>& ray, const TriangleRay& triangle_ray, Leaf leaf, Real t_max) const
        requires packed
    {
        return packets_.occluded(triangle_ray.packed_ray, leaf.first, leaf.count, ray.t_min, t_max);
    }

    // Closest hit along `ray` (object space) below t_max; lowers t_max and fills t, primitive,
    // barycentrics. cull_back_faces skips triangles whose winding faces away from the ray
    // (a camera ray's rule, geometry/backface_culling.hpp): a choice at run time, tested only
    // where a triangle is hit, so every route through the index is compiled once for both.
    bool intersect(const Ray<Real>& ray, Real& t_max, Hit<Real>& hit, bool cull_back_faces) const {
        return intersect(ray, TraversalRay(ray), TriangleRay(ray), t_max, hit, cull_back_faces);
    }

    // The same with the ray's traversal and triangle set-up made by the caller, who may share
    // them between meshes in one space (SceneIndex, for meshes in world space).
    bool intersect(const Ray<Real>& ray, const TraversalRay& traversal_ray, const TriangleRay& triangle_ray, Real& t_max,
                   Hit<Real>& hit, bool cull_back_faces) const {
        const Prepared& prepared = triangle_ray.prepared;
        if constexpr (packed) {
            const typename Packets::PackedRay& packed_ray = triangle_ray.packed_ray;
            bool found = false;
            index_.traverse_closest(traversal_ray, ray.t_min, t_max, [&](std::uint32_t first, std::uint32_t count, Real& t_limit) {
                const bool leaf_hit =
                    packets_.intersect(packed_ray, ray.direction, first, count, ray.t_min, t_limit, hit, cull_back_faces);
                found |= leaf_hit;
                return leaf_hit;
            }, [&](std::uint32_t first) PRISM_PREFETCH_INLINE { packets_.prefetch(first); });
            return found;
        }
        bool found = false;
        index_.traverse_closest(traversal_ray, ray.t_min, t_max, [&](std::uint32_t first, std::uint32_t count, Real& t_limit) {
            bool leaf_hit = false;
            for (std::uint32_t slot = first; slot < first + count; ++slot) {
                const auto& p = triangles_[slot];
                if (cull_back_faces && glm::dot(Vec3<Real>(glm::cross(p[1] - p[0], p[2] - p[0])), ray.direction) > 0) continue;
                TriangleHit<Real> triangle_hit;
                if (Intersector::intersect(prepared, p[0], p[1], p[2], ray.t_min, t_limit, triangle_hit)) {
                    t_limit = triangle_hit.t;
                    hit.t = triangle_hit.t;
                    hit.primitive = slot;
                    hit.b1 = triangle_hit.b1;
                    hit.b2 = triangle_hit.b2;
                    leaf_hit = true;
                }
            }
            found |= leaf_hit;
            return leaf_hit;
        });
        return found;
    }

    bool occluded(const Ray<Real>& ray, Real t_max) const {
        return occluded(ray, TraversalRay(ray), TriangleRay(ray), t_max);
    }

    // The same with the ray's set-up made by the caller, as for intersect.
    bool occluded(const Ray<Real>& ray, const TraversalRay& traversal_ray, const TriangleRay& triangle_ray, Real t_max) const {
        const Prepared& prepared = triangle_ray.prepared;
        if constexpr (packed) {
            const typename Packets::PackedRay& packed_ray = triangle_ray.packed_ray;
            return index_.traverse_any(traversal_ray, ray.t_min, t_max, [&](std::uint32_t first, std::uint32_t count, Real& t_limit) {
                return packets_.occluded(packed_ray, first, count, ray.t_min, t_limit);
            }, [&](std::uint32_t first) PRISM_PREFETCH_INLINE { packets_.prefetch(first); });
        }
        return index_.traverse_any(traversal_ray, ray.t_min, t_max, [&](std::uint32_t first, std::uint32_t count, Real& t_limit) {
            for (std::uint32_t slot = first; slot < first + count; ++slot) {
                const auto& p = triangles_[slot];
                TriangleHit<Real> triangle_hit;
                // Open at t_max, like spheres and planes: a shadow ray aimed at a point on a
                // surface is not blocked by that surface.
                if (Intersector::intersect(prepared, p[0], p[1], p[2], ray.t_min, t_limit, triangle_hit) &&
                    triangle_hit.t < t_limit)
                    return true;
            }
            return false;
        });
    }

    // intersect for the rays of `lanes` at once (bit i: rays[i], set up as traversal[i] and
    // triangle[i]), each from t_min[i] up to its own t_max[i], which is lowered as hits[i] is
    // filled (WideBvhTree::traverse_closest_lanes; the leaf's packet test of each ray). Returns
    // the rays hit. A ray's closest hit is intersect's wherever it is the one nearest hit, and
    // `tied` gets the rays whose hit may depend on the order the leaves were visited in: a
    // leaf's hit at the t_max it was given (the packet test takes a later tie). With a Storage
    // wider than Real (DoubleRefine), two hits rounding to one Real t are such a tie too, but
    // the later one is refused where its Storage t lies above the rounded t_max (a vertex
    // shared by two leaves' triangles): so each leaf is tested up to the next Real above
    // t_max, where such a hit is taken and the ray counted tied. The caller traces tied rays
    // again with intersect, from what they had before.
    std::uint32_t intersect_lanes(const Ray<Real>* rays, const TraversalRay* traversal, const TriangleRay* triangle,
                                  const Real* t_min, Real* t_max, std::uint32_t lanes, Hit<Real>* hits,
                                  std::uint32_t& tied, bool cull_back_faces) const
        requires packed
    {
        return index_.traverse_closest_lanes(
            traversal, t_min, t_max, lanes, [&](std::uint32_t first, std::uint32_t count, std::uint32_t testing) {
                std::uint32_t hit = 0;
                for (; testing != 0; testing &= testing - 1) {
                    const int i = std::countr_zero(testing);
                    const Real before = t_max[i];
                    if constexpr (!std::is_same_v<Storage, Real>) t_max[i] = std::nextafter(before, infinity<Real>);
                    if (!packets_.intersect(triangle[i].packed_ray, rays[i].direction, first, count, rays[i].t_min,
                                            t_max[i], hits[i], cull_back_faces)) {
                        t_max[i] = before;
                        continue;
                    }
                    hit |= std::uint32_t(1) << i;
                    if (!(t_max[i] < before)) tied |= std::uint32_t(1) << i;
                }
                return hit;
            });
    }

    // occluded for the rays of `lanes` at once (bit i: rays[i], set up as traversal[i] and
    // triangle[i]), each up to its own t_max: the blocked ones, each answered as occluded
    // answers it (WideBvhTree::traverse_any_lanes; the leaf's packet test of each ray).
    std::uint32_t occluded_lanes(const Ray<Real>* rays, const TraversalRay* traversal, const TriangleRay* triangle,
                                 const Real* t_min, const Real* t_max, std::uint32_t lanes) const
        requires packed
    {
        return index_.traverse_any_lanes(traversal, t_min, t_max, lanes,
                                         [&](std::uint32_t first, std::uint32_t count, std::uint32_t testing) {
                                             std::uint32_t blocked = 0;
                                             for (; testing != 0; testing &= testing - 1) {
                                                 const int i = std::countr_zero(testing);
                                                 if (packets_.occluded(triangle[i].packed_ray, first, count, rays[i].t_min, t_max[i]))
                                                     blocked |= std::uint32_t(1) << i;
                                             }
                                             return blocked;
                                         });
    }

private:
    void build(std::span<const scene::Mesh* const> parts, std::uint32_t max_leaf_size) {
        for (const scene::Mesh* part : parts) triangle_count_ += part->triangles.size();
        build_index(parts, max_leaf_size);
        // The packets hold the leaves' triangles: the plain copy would be read by nothing.
        if constexpr (packed) {
            triangles_.clear();
            triangles_.shrink_to_fit();
        }
    }

    // The index over the parts' triangles (their boxes widened where Storage is wider than
    // Real), and the triangles copied into its slots, with their packets.
    void build_index(std::span<const scene::Mesh* const> parts, std::uint32_t max_leaf_size) {
        // Triangle i of the parts laid end to end: part p holds [first[p], first[p + 1]). Found
        // by search rather than kept per triangle (two pointer arrays of the triangle count).
        std::vector<std::uint32_t> first{0};
        for (const scene::Mesh* part : parts) first.push_back(first.back() + std::uint32_t(part->triangles.size()));
        const auto part_of = [&](std::uint32_t i) {
            return std::size_t(std::upper_bound(first.begin() + 1, first.end(), i) - (first.begin() + 1));
        };
        const auto face_of = [&](std::uint32_t i, std::size_t part) -> const std::array<std::uint32_t, 3>& {
            return parts[part]->triangles[i - first[part]];
        };
        const auto box_of = [&](std::uint32_t i) {
            const std::size_t part = part_of(i);
            return triangle_box(*parts[part], face_of(i, part));
        };
        if constexpr (requires { Index::build(std::uint32_t(0), box_of); }) {
            // The index takes the boxes as they are made; its root box is the one the loop
            // below would find (the same boxes extended in the same order).
            const std::uint32_t count = std::uint32_t(triangle_count_);
            if constexpr (requires { Index::build(count, box_of, BvhBuildOptions{}); })
                index_ = max_leaf_size != 0 ? Index::build(count, box_of, BvhBuildOptions{.max_leaf_size = max_leaf_size})
                                            : Index::build(count, box_of);
            else
                index_ = Index::build(count, box_of);
            bounds_ = index_.bounds();
        } else {
            std::vector<Aabb<Real>> boxes;
            boxes.reserve(triangle_count_);
            for (std::uint32_t i = 0; i < std::uint32_t(triangle_count_); ++i) {
                boxes.push_back(box_of(i));
                bounds_.extend(boxes.back());
            }
            index_ = Index::build(boxes);
        }
        // An index may repeat primitives to pad its leaves (the wide BVH): slots then outnumber
        // triangles, and the repeats are copies that no leaf callback reports.
        const auto& order = index_.primitive_indices();
        const auto triangle = [&](std::uint32_t i) -> std::array<Vec3<Storage>, 3> {
            const std::size_t part = part_of(i);
            const auto& face = face_of(i, part);
            const auto& positions = parts[part]->positions;
            return {Vec3<Storage>(positions[face[0]]), Vec3<Storage>(positions[face[1]]), Vec3<Storage>(positions[face[2]])};
        };
        // Resized without clearing (a HugePageVector) and written slot by slot: large meshes
        // copy theirs in parallel.
        triangles_.resize(order.size());
        const auto copy = [&](std::size_t first, std::size_t end) {
            for (std::size_t slot = first; slot < end; ++slot) triangles_[slot] = triangle(order[slot]);
        };
        constexpr std::size_t grain = 16384;  // slots per task
        for_each_run(order.size(), grain, copy);
        if constexpr (packed) packets_ = Packets(triangles_, order);
    }

    static Aabb<Real> triangle_box(const scene::Mesh& mesh, const std::array<std::uint32_t, 3>& face) {
        Aabb<Real> box;
        for (std::uint32_t v : face) box.extend(Vec3<Real>(mesh.positions[v]));
        // Vertices kept wider than Real are rounded for the box: widen it by one ulp on each
        // side so the box still contains the triangle the intersector tests.
        if constexpr (!std::is_same_v<Storage, Real>) {
            for (int axis = 0; axis < 3; ++axis) {
                box.min[axis] = next_down(box.min[axis]);
                box.max[axis] = next_up(box.max[axis]);
            }
        }
        return box;
    }

    std::size_t triangle_count_ = 0;
    Aabb<Real> bounds_;
    Index index_;
    [[no_unique_address]] Packets packets_;
    // In slot order, for the leaf tests; none where the packets hold the triangles.
    HugePageVector<std::array<Vec3<Storage>, 3>> triangles_;
};

}  // namespace prism
