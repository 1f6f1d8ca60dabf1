// SceneIndex's batches side by side (geometry/scene_index.hpp, route()): with a ray in each SIMD
// lane at the leaves a scene of few objects tests directly, or several rays through the index
// together, whose nodes' tests then overlap instead of each waiting on the one before. Every
// ray's answer is the one it gets alone, to the bit: a closest hit depends on the order in which
// leaves are visited only when two candidates tie, and a ray whose hit in a lane traversal came
// at exactly the t_max it was given is traced again on its own (the one tie rule).
// Included by scene_index.hpp, after the class: these are its members' definitions.
#pragma once

#include <prism/geometry/scene_index.hpp>

namespace prism {

// The rays of `lanes` taken to an instance's object space and set up there, each as
// occludes and intersect_instance set up one (occludes_in_object_space,
// intersect_in_object_space).
template <Scalar Real, class Policy, bool MotionBlur>
    requires AccelerationPolicy<Policy, Real>
struct SceneIndex<Real, Policy, MotionBlur>::ObjectSpaceRays {
    Unconstructed<Ray<Real>, index_lanes> ray;
    Unconstructed<TraversalRay, index_lanes> traversal;
    Unconstructed<TriangleRay, index_lanes> triangle;

    void make(const Placement<Real>& instance, const Ray<Real>* rays, std::uint32_t lanes) {
        for (; lanes != 0; lanes &= lanes - 1) {
            const std::size_t i = std::size_t(std::countr_zero(lanes));
            const Ray<Real>& local = ray.make(i, instance.template ray_to_object<MotionBlur>(rays[i]));
            traversal.make(i, local);
            triangle.make(i, local);
        }
    }
};

// The world-space set-up of up to index_lanes rays, each as intersect and occluded make it
// for one: its traversal set-up and its t range, and its triangle set-up once it first
// enters a world-space mesh (triangles).
template <Scalar Real, class Policy, bool MotionBlur>
    requires AccelerationPolicy<Policy, Real>
struct SceneIndex<Real, Policy, MotionBlur>::WorldSpaceRays {
    const Ray<Real>* rays;
    Unconstructed<TraversalRay, index_lanes> traversal;
    Unconstructed<TriangleRay, index_lanes> triangle;
    std::uint32_t made = 0;  // the lanes whose triangle set-up is made
    alignas(64) Real t_min[index_lanes];
    alignas(64) Real t_max[index_lanes];

    WorldSpaceRays(const Ray<Real>* rays_, int count) : rays(rays_) {
        for (int i = 0; i < count; ++i) {
            traversal.make(std::size_t(i), rays[i]);
            t_min[i] = rays[i].t_min;
            t_max[i] = rays[i].t_max;
        }
    }
    // The triangle set-ups, made for the lanes of `lanes` that have none yet.
    const TriangleRay* triangles(std::uint32_t lanes) {
        for (std::uint32_t missing = lanes & ~made; missing != 0; missing &= missing - 1) {
            const int i = std::countr_zero(missing);
            triangle.make(std::size_t(i), rays[i]);
        }
        made |= lanes;
        return triangle.data();
    }
};

// The lanes of rays[0, n), less those of `skip`, whose ray may reach `leaf`: intersect's
// and occluded's own leaves_box test, ray by ray.
template <Scalar Real, class Policy, bool MotionBlur>
    requires AccelerationPolicy<Policy, Real>
inline std::uint32_t SceneIndex<Real, Policy, MotionBlur>::lanes_reaching(const typename Mesh::Leaf& leaf, const Ray<Real>* rays, int n,
                                                           std::uint32_t skip) {
    std::uint32_t lanes = 0;
    for (int i = 0; i < n; ++i)
        if (!((skip >> i) & 1) && !leaves_box(leaf.box, rays[i])) lanes |= std::uint32_t(1) << i;
    return lanes;
}

// The rays' t_max, a lane each (the lanes past n copy ray 0's, as RayLanes does).
template <Scalar Real, class Policy, bool MotionBlur>
    requires AccelerationPolicy<Policy, Real>
template <class Packets>
inline typename Packets::LanePack SceneIndex<Real, Policy, MotionBlur>::lanes_t_max(const Ray<Real>* rays, int n) {
    alignas(64) Real limits[Packets::ray_lanes];
    for (int i = 0; i < Packets::ray_lanes; ++i) limits[i] = rays[i < n ? i : 0].t_max;
    return Packets::LanePack::load(limits);
}

// The closest hits of rays[0, count) side by side (every surface but the planes, which the
// entry tests last), each as closest_one gives it alone: its
// ray.t_max lowered to the hit and hits[i] filled, bit i of the answer set, where it hits
// (count <= 32). BatchRoute::leaf_lanes: the world meshes' leaves are tested against several
// rays at once (TriangleMesh::intersect_leaf_lanes, lane by lane the leaf test's bits),
// leaf after leaf of the root, then the direct spheres likewise
// (intersect_direct_spheres_lanes); a ray whose hits in
// two leaves tie is traced again alone (closest_one), as intersect_root_leaves does.
// BatchRoute::index_lanes: the rays traverse the index together (intersect_through_index).
template <Scalar Real, class Policy, bool MotionBlur>
    requires AccelerationPolicy<Policy, Real>
std::uint32_t SceneIndex<Real, Policy, MotionBlur>::closest_dense(BatchRoute way, Ray<Real>* rays, Hit<Real>* hits, int count,
                                                                  bool cull) const {
    std::uint32_t found = 0;
    if (way == BatchRoute::index_lanes) {
        if constexpr (Mesh::packed) {
            for (int first = 0; first < count; first += index_lanes)
                found |= intersect_through_index(rays + first, hits + first, std::min(index_lanes, count - first), cull)
                         << first;
        }
        return found;
    }
    if constexpr (Mesh::packed) {
        if constexpr (Mesh::Packets::tests_ray_lanes) {
            using Packets = typename Mesh::Packets;
            constexpr int width = Packets::ray_lanes;
            for (int first = 0; first < count; first += width) {
                Ray<Real>* const group = rays + first;
                Hit<Real>* const group_hits = hits + first;
                const int n = std::min(width, count - first);
                std::optional<typename Packets::RayLanes> lanes_ray;  // made for the first leaf the rays may reach
                std::uint32_t world_hits = 0, tied = 0;
                // What a ray had before its first leaf hit: a tied ray is traced again from there.
                Real given_t_max[width];
                Hit<Real> given_hits[width];
                for (const WorldMeshes& mesh_group : world_meshes_) {
                    const typename Mesh::RootLeaves& leaves = *mesh_group.leaves;
                    const Mesh& index = index_of(mesh_group);
                    typename Packets::LaneHits lane_hits;
                    lane_hits.t_max = lanes_t_max<Packets>(group, n);
                    // The root's leaves in slot order, each lane's t_max lowered by the leaves
                    // before (intersect_root_leaves tests each from the ray's own t_max: a
                    // leaf's closest candidate is the same under the lowered one wherever it
                    // is nearer, and is found at exactly the lowered t_max where it ties).
                    for (int k = 0; k < leaves.count; ++k) {
                        const typename Mesh::Leaf& leaf = leaves.leaf[std::size_t(k)];
                        const std::uint32_t lanes = lanes_reaching(leaf, group, n, 0);
                        if (lanes == 0) continue;
                        if (!lanes_ray) lanes_ray.emplace(group, n);
                        lane_hits.found = 0;
                        index.intersect_leaf_lanes(*lanes_ray, leaf, lanes, lane_hits, cull);
                        std::uint32_t taken = lane_hits.found & lanes;
                        if (taken == 0) continue;
                        alignas(64) Real t[width], b1[width], b2[width];
                        lane_hits.t_max.store(t);
                        lane_hits.b1.store(b1);
                        lane_hits.b2.store(b2);
                        for (; taken != 0; taken &= taken - 1) {
                            const int i = std::countr_zero(taken);
                            const std::uint32_t bit = std::uint32_t(1) << i;
                            Hit<Real>& hit = group_hits[i];
                            // Found at exactly the hit of an earlier leaf: which of the two a
                            // traversal keeps depends on its order of visits.
                            if (!(world_hits & bit)) {
                                given_t_max[i] = group[i].t_max;
                                given_hits[i] = hit;
                            } else if (t[i] == group[i].t_max) {
                                tied |= bit;
                            } else {
                                tied &= ~bit;
                            }
                            group[i].t_max = t[i];
                            hit.t = t[i];
                            hit.primitive = lane_hits.slot[std::size_t(i)];
                            hit.b1 = b1[i];
                            hit.b2 = b2[i];
                            if (mesh_group.index) mesh_group.attribute(index.source_triangle(hit.primitive), hit);
                            else hit.object = mesh_group.objects[0];
                            world_hits |= bit;
                        }
                    }
                }
                static_assert(width <= Direct::width, "a group of rays fits the direct lanes");
                if (direct_.has_spheres()) direct_.intersect_spheres_lanes(group, group_hits, n, world_hits);
                // The tied rays (an edge shared by two leaves), each traced again alone.
                for (; tied != 0; tied &= tied - 1) {
                    const int i = std::countr_zero(tied);
                    group[i].t_max = given_t_max[i];
                    group_hits[i] = given_hits[i];
                    if (!closest_one(group[i], group_hits[i], cull)) world_hits &= ~(std::uint32_t(1) << i);
                }
                found |= world_hits << first;
            }
        }
    }
    return found;
}

// Whether each of rays[0, count) is occluded, side by side (bit i for rays[i]; count <=
// 32), each as occluded_one answers it. BatchRoute::leaf_lanes: the world meshes' leaves and the
// direct spheres with a ray in each lane (the shadow rays of a row's camera hits to one
// light), the planes ray by ray. BatchRoute::index_lanes: through the index together
// (occluded_through_index).
template <Scalar Real, class Policy, bool MotionBlur>
    requires AccelerationPolicy<Policy, Real>
std::uint32_t SceneIndex<Real, Policy, MotionBlur>::occluded_dense(BatchRoute way, const Ray<Real>* rays, int count) const {
    std::uint32_t blocked = 0;
    if (way == BatchRoute::index_lanes) {
        if constexpr (Mesh::packed) {
            for (int first = 0; first < count; first += index_lanes)
                blocked |= occluded_through_index(rays + first, std::min(index_lanes, count - first)) << first;
        }
        return blocked;
    }
    if constexpr (Mesh::packed) {
        if constexpr (Mesh::Packets::tests_ray_lanes) {
            using Packets = typename Mesh::Packets;
            constexpr int width = Packets::ray_lanes;
            for (int first = 0; first < count; first += width) {
                const Ray<Real>* const group = rays + first;
                const int n = std::min(width, count - first);
                const std::uint32_t present = (std::uint32_t(1) << n) - 1;
                std::uint32_t found = 0;
                std::optional<typename Packets::RayLanes> lanes_ray;
                std::optional<typename Packets::LanePack> t_max;
                for (const WorldMeshes& mesh_group : world_meshes_)
                    for (int k = 0; k < mesh_group.leaves->count; ++k) {
                        const typename Mesh::Leaf& leaf = mesh_group.leaves->leaf[std::size_t(k)];
                        const std::uint32_t lanes = lanes_reaching(leaf, group, n, found);
                        if (lanes == 0) continue;
                        if (!lanes_ray) {
                            lanes_ray.emplace(group, n);
                            t_max = lanes_t_max<Packets>(group, n);
                        }
                        found |= index_of(mesh_group).occluded_leaf_lanes(*lanes_ray, leaf, lanes, *t_max);
                    }
                if (found != present && direct_.has_spheres())
                    direct_.template intersect_spheres_lanes<true>(group, nullptr, n, found);
                // No direct meshes (intersection_batches): the planes, ray by ray, where there are any.
                if (planes_.empty()) {
                    blocked |= found << first;
                    continue;
                }
                for (int i = 0; i < n; ++i)
                    if (((found >> i) & 1) || planes_.occludes(group[i])) blocked |= std::uint32_t(1) << (first + i);
            }
        }
    }
    return blocked;
}

// closest_dense in a scene traversed through its index (no direct form), for up to
// index_lanes rays: each world mesh's closest hits for the rays together
// (TriangleMesh::intersect_lanes: each ray set up and tested as intersect_indexed sets it up
// and tests it, the leaves visited in one order for all), then each ray's top level on its
// own (intersect_top). A pixel's camera rays reach the same nodes, whose
// tests then overlap instead of each waiting on the one before. A ray whose hit in a mesh
// may depend on that order (a tie) is traced through that mesh again on its own, from
// where it was before the mesh, so every ray's hit is intersect's.
template <Scalar Real, class Policy, bool MotionBlur>
    requires AccelerationPolicy<Policy, Real>
std::uint32_t SceneIndex<Real, Policy, MotionBlur>::intersect_through_index(Ray<Real>* rays, Hit<Real>* hits, int count,
                                                                            bool cull) const {
    const std::uint32_t present = (std::uint32_t(1) << count) - 1;
    WorldSpaceRays world(rays, count);
    Real* const t_min = world.t_min;
    Real* const t_max = world.t_max;
    auto& traversal = world.traversal;
    std::uint32_t found = 0;
    for (const WorldMeshes& group : world_meshes_) {
        const Mesh& index = index_of(group);
        std::uint32_t lanes = 0;
        for (std::uint32_t rest = present; rest != 0; rest &= rest - 1) {
            const int i = std::countr_zero(rest);
            if (index.enters(traversal[std::size_t(i)], t_min[i], t_max[i])) lanes |= std::uint32_t(1) << i;
        }
        if (lanes == 0) continue;
        const TriangleRay* const world_triangle = world.triangles(lanes);
        // What a tied ray is traced again from.
        std::array<Real, index_lanes> t_before;
        Unconstructed<Hit<Real>, index_lanes> hit_before;
        for (std::uint32_t rest = lanes; rest != 0; rest &= rest - 1) {
            const int i = std::countr_zero(rest);
            t_before[std::size_t(i)] = t_max[i];
            hit_before.make(std::size_t(i), hits[i]);
        }
        std::uint32_t tied = 0;
        std::uint32_t group_hits =
            index.intersect_lanes(rays, traversal.data(), world_triangle, t_min, t_max, lanes, hits, tied, cull);
        for (; tied != 0; tied &= tied - 1) {
            const int i = std::countr_zero(tied);
            const std::uint32_t bit = std::uint32_t(1) << i;
            t_max[i] = t_before[std::size_t(i)];
            hits[i] = hit_before[std::size_t(i)];
            rays[i].t_max = t_max[i];
            const bool hit = index.intersect(rays[i], traversal[std::size_t(i)], world_triangle[i], t_max[i], hits[i], cull);
            group_hits = hit ? group_hits | bit : group_hits & ~bit;
        }
        for (std::uint32_t rest = group_hits; rest != 0; rest &= rest - 1) {
            const int i = std::countr_zero(rest);
            Hit<Real>& hit = hits[i];
            if (group.index) group.attribute(index.source_triangle(hit.primitive), hit);
            else hit.object = group.objects[0];
        }
        found |= group_hits;
    }
    std::uint32_t answer = 0;
    if (direct_.chosen() || top_objects_.empty()) {
        for (int i = 0; i < count; ++i) {
            rays[i].t_max = t_max[i];
            // Made again where a top-level mesh in world space needs it (its set-up is the
            // ray's alone, so the same bits).
            std::optional<TriangleRay> world_triangle_ray;
            if (intersect_top(rays[i], hits[i], (found >> i) & 1, traversal[std::size_t(i)], world_triangle_ray, cull))
                answer |= std::uint32_t(1) << i;
        }
        return answer;
    }
    // The top level's instances for the rays together, as intersect_top tests them one ray
    // at a time; a ray tied anywhere in it is traced through it again on its own.
    std::array<Real, index_lanes> t_before;
    Unconstructed<Hit<Real>, index_lanes> hit_before;
    for (int i = 0; i < count; ++i) {
        t_before[std::size_t(i)] = t_max[i];
        hit_before.make(std::size_t(i), hits[i]);
    }
    std::uint32_t tied = 0;
    const auto& order = top_.primitive_indices();
    const std::uint32_t top_hits = top_.traverse_closest_lanes(
        traversal.data(), t_min, t_max, present, [&](std::uint32_t first, std::uint32_t objects, std::uint32_t testing) {
            std::uint32_t hit = 0;
            for (std::uint32_t k = first; k < first + objects; ++k) {
                const std::uint32_t object = top_objects_[order[k]];
                const Placement<Real>& instance = placements_[object];
                std::uint32_t instance_hits = 0;
                if (instance.kind == Kind::mesh && instance.template in_world_space<MotionBlur>()) {
                    const TriangleRay* const world_triangle = world.triangles(testing);
                    const Mesh& mesh = mesh_at(instance.shape);
                    instance_hits = mesh.intersect_lanes(rays, traversal.data(), world_triangle, t_min, t_max, testing, hits, tied, cull);
                } else {
                    instance_hits = intersect_in_object_space(instance, rays, t_min, t_max, testing, hits, tied, cull);
                }
                for (std::uint32_t rest = instance_hits; rest != 0; rest &= rest - 1)
                    hits[std::countr_zero(rest)].object = object;
                hit |= instance_hits;
            }
            return hit;
        });
    const std::uint32_t world_found = found;
    found |= top_hits;
    for (int i = 0; i < count; ++i) {
        const std::uint32_t bit = std::uint32_t(1) << i;
        if (tied & bit) {
            t_max[i] = t_before[std::size_t(i)];
            hits[i] = hit_before[std::size_t(i)];
            rays[i].t_max = t_max[i];
            std::optional<TriangleRay> world_triangle_ray;
            if (intersect_top(rays[i], hits[i], (world_found & bit) != 0, traversal[std::size_t(i)], world_triangle_ray,
                              cull))
                answer |= bit;
            continue;
        }
        rays[i].t_max = t_max[i];
        answer |= found & bit;
    }
    return answer;
}

// intersect_instance for the rays of `lanes` and an object not in world space: each ray
// taken to its object space and set up there as intersect_instance does; `tied` as
// TriangleMesh::intersect_lanes sets it (a sphere's hit at the t_max it was given, too).
template <Scalar Real, class Policy, bool MotionBlur>
    requires AccelerationPolicy<Policy, Real>
std::uint32_t SceneIndex<Real, Policy, MotionBlur>::intersect_in_object_space(const Placement<Real>& instance, const Ray<Real>* rays, const Real* t_min, Real* t_max,
                                        std::uint32_t lanes, Hit<Real>* hits, std::uint32_t& tied, bool cull) const {
    std::uint32_t hit = 0;
    if (instance.kind != Kind::mesh) {
        for (; lanes != 0; lanes &= lanes - 1) {
            const int i = std::countr_zero(lanes);
            Real t;
            if (!spheres_[instance.shape].intersect(instance.template ray_to_object<MotionBlur>(rays[i]), rays[i].t_min, t_max[i], t)) continue;
            if (!(t < t_max[i])) tied |= std::uint32_t(1) << i;
            t_max[i] = t;
            hits[i].t = t;
            hits[i].primitive = 0;
            hits[i].b1 = hits[i].b2 = 0;
            hit |= std::uint32_t(1) << i;
        }
        return hit;
    }
    ObjectSpaceRays local;
    local.make(instance, rays, lanes);
    const Mesh& mesh = mesh_at(instance.shape);
    return mesh.intersect_lanes(local.ray.data(), local.traversal.data(), local.triangle.data(), t_min, t_max, lanes, hits, tied, cull);
}

// occluded_dense in a scene traversed through its index (no direct form), for up to
// index_lanes rays: every level's any hits found for the rays together, each ray set up and
// tested as occluded sets it up and tests it (WideBvhTree::traverse_any_lanes), so each
// ray's answer is occluded's. A row's shadow rays to one light reach the same nodes, whose
// tests then overlap instead of each waiting on the one before (hw2 horse_instanced's
// three instanced horses: the shadow rays were a third of its time).
template <Scalar Real, class Policy, bool MotionBlur>
    requires AccelerationPolicy<Policy, Real>
std::uint32_t SceneIndex<Real, Policy, MotionBlur>::occluded_through_index(const Ray<Real>* rays, int count) const {
    const std::uint32_t present = (std::uint32_t(1) << count) - 1;
    WorldSpaceRays world(rays, count);
    const Real* const t_min = world.t_min;
    const Real* const t_max = world.t_max;
    auto& traversal = world.traversal;
    std::uint32_t blocked = 0;
    for (const WorldMeshes& group : world_meshes_) {
        const Mesh& index = index_of(group);
        std::uint32_t lanes = 0;
        for (std::uint32_t rest = present & ~blocked; rest != 0; rest &= rest - 1) {
            const int i = std::countr_zero(rest);
            if (index.enters(traversal[std::size_t(i)], t_min[i], t_max[i])) lanes |= std::uint32_t(1) << i;
        }
        if (lanes == 0) continue;
        blocked |= index.occluded_lanes(rays, traversal.data(), world.triangles(lanes), t_min, t_max, lanes);
    }
    if (direct_.chosen()) {
        for (std::uint32_t rest = present & ~blocked; rest != 0; rest &= rest - 1) {
            const int i = std::countr_zero(rest);
            if (occluded_direct(rays[i])) blocked |= std::uint32_t(1) << i;
        }
        return blocked;
    }
    if (!top_objects_.empty() && blocked != present) {
        const auto& order = top_.primitive_indices();
        blocked |= top_.traverse_any_lanes(
            traversal.data(), t_min, t_max, present & ~blocked,
            [&](std::uint32_t first, std::uint32_t objects, std::uint32_t testing) {
                std::uint32_t hit = 0;
                for (std::uint32_t k = first; k < first + objects && (testing & ~hit) != 0; ++k) {
                    const Placement<Real>& instance = placements_[top_objects_[order[k]]];
                    const std::uint32_t lanes = testing & ~hit;
                    if (instance.kind == Kind::mesh && instance.template in_world_space<MotionBlur>()) {
                        hit |= mesh_at(instance.shape).occluded_lanes(rays, traversal.data(), world.triangles(lanes),
                                                                      t_min, t_max, lanes);
                        continue;
                    }
                    hit |= occludes_in_object_space(instance, rays, t_min, t_max, lanes);
                }
                return hit;
            });
    }
    for (std::uint32_t rest = present & ~blocked; rest != 0; rest &= rest - 1) {
        const int i = std::countr_zero(rest);
        if (planes_.occludes(rays[i])) blocked |= std::uint32_t(1) << i;
    }
    return blocked;
}

// occludes for the rays of `lanes` and an object not in world space: each ray taken to
// its object space and set up there as occludes does.
template <Scalar Real, class Policy, bool MotionBlur>
    requires AccelerationPolicy<Policy, Real>
std::uint32_t SceneIndex<Real, Policy, MotionBlur>::occludes_in_object_space(const Placement<Real>& instance, const Ray<Real>* rays, const Real* t_min,
                                       const Real* t_max, std::uint32_t lanes) const {
    std::uint32_t blocked = 0;
    if (instance.kind != Kind::mesh) {
        for (; lanes != 0; lanes &= lanes - 1) {
            const int i = std::countr_zero(lanes);
            Real t;
            if (spheres_[instance.shape].intersect(instance.template ray_to_object<MotionBlur>(rays[i]), t_min[i], t_max[i], t) && t < t_max[i])
                blocked |= std::uint32_t(1) << i;
        }
        return blocked;
    }
    ObjectSpaceRays local;
    local.make(instance, rays, lanes);
    return mesh_at(instance.shape).occluded_lanes(local.ray.data(), local.traversal.data(), local.triangle.data(), t_min,
                                                  t_max, lanes);
}

}  // namespace prism
