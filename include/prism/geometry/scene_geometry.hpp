// All the geometry of a scene in the renderer's precision: meshes (each with its own index),
// spheres and planes, placed by instances under a top-level index. This is the two-level
// hierarchy: a MeshInstance costs one instance record, never a copy of its mesh or its BVH.
// The meshes already in world space (no transformation, not moving, not instanced) share one
// index over all their triangles instead, traversed beside the top level (merged_meshes).
// It satisfies Accelerator: intersect (closest hit) and occluded (any hit).
// With MotionBlur, an object with a MotionBlur translation m is at M p + m t at shutter instant
// t: rays are moved back by m t before entering its object space, and its world box covers the
// whole sweep (the boxes at t = 0 and t = 1 together, exact for a translation).
// spawn_origin gives leaving rays their origin from the hit point's floating-point error bound
// (geometry/surface_error.hpp) instead of a scene-tuned epsilon.
#pragma once

#include <prism/accel/accelerator.hpp>
#include <prism/geometry/backface_culling.hpp>
#include <prism/geometry/hit.hpp>
#include <prism/geometry/ray_batch.hpp>
#include <prism/geometry/sphere.hpp>
#include <prism/geometry/surface_error.hpp>
#include <prism/geometry/triangle_mesh.hpp>
#include <prism/math/transform.hpp>
#include <prism/memory/unconstructed.hpp>
#include <prism/scene/scene.hpp>
#include <prism/simd/pack.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <span>
#include <type_traits>
#include <vector>

namespace prism {

template <Scalar Real>
struct PlaneShape {
    // The hit point reprojected onto the plane, p - n ((p - q) . n), with a bound on its error
    // along each axis. Planes are not in pbrt's set, so the bound is derived here: the exact
    // reprojection of the computed p lies on the plane whatever p's own error; computing it
    // rounds p - q and the dot product (gamma(4) of sum |n_i| (|p_i| + |q_i|)) and the final
    // subtraction (u |p'| and u |n d|). gamma(6) (|p| + |p'| + |q|) + gamma(2) |d| covers them
    // per axis, and d . |n| of it bounds the distance to the plane.
    PointWithError<Real> hit_point(const Vec3<Real>& approximate) const {
        const Real d = glm::dot(approximate - point, normal);
        const Vec3<Real> projected = approximate - normal * d;
        return {projected, gamma<Real>(6) * (abs_each(approximate) + abs_each(projected) + abs_each(point)) +
                               Vec3<Real>(gamma<Real>(2) * std::abs(d))};
    }

    Vec3<Real> point{0};
    Vec3<Real> normal{0, 1, 0};  // unit

    // Forced inline: out of line, the planes' loop in front of every shadow ray's light took 17%
    // of hw2 mirror_room (5 planes).
    [[gnu::always_inline]] bool intersect(const Ray<Real>& ray, Real t_min, Real t_max, Real& t_hit) const {
        const Real denominator = glm::dot(ray.direction, normal);
        if (denominator == 0) return false;
        const Real numerator = glm::dot(point - ray.origin, normal);
        // Opposite signs (or a zero numerator) give a t of at most 0, which no t_min >= 0
        // accepts: the division is left out (planes behind the ray, half of a room's walls).
        if (t_min >= 0 && (numerator == 0 || std::signbit(numerator) != std::signbit(denominator))) return false;
        const Real t = numerator / denominator;
        if (!(t > t_min && t <= t_max)) return false;
        t_hit = t;
        return true;
    }
};

template <Scalar Real, class Policy, bool MotionBlur = false>
    requires AccelerationPolicy<Policy, Real>
class SceneGeometry {
public:
    using Index = typename Policy::template Index<Real>;

    explicit SceneGeometry(const scene::Scene& scene) {
        const std::vector<bool> merged = merged_meshes(scene);
        // A single merged mesh needs no merged index: it keeps its own, read without the
        // translation a merged index's hits need (a cache miss per hit ray on the 766k-triangle
        // dragon: 5-9% of its camera rays' time).
        const bool alone = std::count(merged.begin(), merged.end(), true) == 1;
        meshes_.reserve(scene.meshes.size());
        for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
            const scene::Mesh& mesh = scene.meshes[m];
            if (merged[m] && !alone) meshes_.emplace_back(mesh, typename Mesh::ShadingOnly{});
            else meshes_.emplace_back(mesh);
            add_instance(Kind::mesh, std::uint32_t(meshes_.size() - 1), mesh.material, mesh.transform,
                         meshes_.back().bounds(), mesh.textures, mesh.motion);
            emitted_.emplace_back(mesh.radiance);
        }
        for (const auto& instance : scene.mesh_instances)
            add_instance(Kind::mesh, std::uint32_t(instance.base_mesh), instance.material, instance.transform,
                         meshes_[instance.base_mesh].bounds(), instance.textures, instance.motion);
        for (const auto& instance : scene.mesh_instances) emitted_.emplace_back(scene.meshes[instance.base_mesh].radiance);
        for (const auto& sphere : scene.spheres) {
            spheres_.push_back({Vec3<Real>(sphere.center), Real(sphere.radius)});
            add_instance(Kind::sphere, std::uint32_t(spheres_.size() - 1), sphere.material, sphere.transform,
                         spheres_.back().bounds(), sphere.textures, sphere.motion);
            emitted_.emplace_back(sphere.radiance);
        }
        // Planes are unbounded, so they stay outside the top-level index and are tested always.
        for (const auto& plane : scene.planes) {
            const glm::dvec3 point = glm::dvec3(plane.transform * glm::dvec4(plane.point, 1.0));
            const glm::dvec3 normal =
                glm::normalize(glm::transpose(glm::inverse(glm::dmat3(plane.transform))) * plane.normal);
            planes_.push_back({Vec3<Real>(point), Vec3<Real>(normal)});
            if (planes_.size() % direct_width == 1) plane_blocks_.emplace_back();
            PlaneBlock& block = plane_blocks_.back();
            const std::size_t lane = (planes_.size() - 1) % direct_width;
            for (int axis = 0; axis < 3; ++axis) {
                block.point[axis][lane] = planes_.back().point[axis];
                block.normal[axis][lane] = planes_.back().normal[axis];
            }
            block.lanes |= std::uint32_t(1) << lane;
            plane_materials_.push_back(std::uint32_t(plane.material));
            plane_textures_.push_back(add_texture_list(plane.textures));
        }
        // One index over the merged meshes, flat and smooth alike (they are culled alike), the
        // instance of mesh m being object m.
        {
            WorldMeshes group;
            std::vector<const scene::Mesh*> parts;
            std::uint32_t triangles = 0;
            for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
                if (!merged[m]) continue;
                parts.push_back(&scene.meshes[m]);
                group.objects.push_back(std::uint32_t(m));
                group.first_triangle.push_back(triangles);
                triangles += std::uint32_t(scene.meshes[m].triangles.size());
            }
            if (parts.size() > 1) group.index.emplace(std::span<const scene::Mesh* const>(parts));
            if (!parts.empty()) world_meshes_.push_back(std::move(group));
        }
        std::vector<Aabb<Real>> boxes;
        for (std::uint32_t object = 0; object < instances_.size(); ++object) {
            bounds_.extend(instances_[object].world_bounds);
            if (object < merged.size() && merged[object]) continue;
            top_objects_.push_back(object);
            boxes.push_back(instances_[object].world_bounds);
        }
        // One instance per leaf where the index takes the option: testing an instance (a
        // transform, then its mesh's own BVH or its sphere) costs far more than the box test
        // that could skip it. With the wide BVH's leaves of up to 8, a scene of a few instances
        // was one leaf, and every ray entered every instance (hw2 ellipsoids, the course's
        // Cornell boxes: 1.0-1.3x the time of the binary BVH before the wide one).
        BvhBuildOptions top_options;
        top_options.max_leaf_size = 1;
        if constexpr (requires { Index::build(boxes, top_options); }) top_ = Index::build(boxes, top_options);
        else top_ = Index::build(boxes);
        choose_direct_top_level(scene);
        choose_direct_world_meshes();
    }

    std::size_t instance_count() const { return instances_.size(); }
    std::size_t triangle_count() const {
        std::size_t total = 0;
        for (const auto& instance : instances_)
            if (instance.kind == Kind::mesh) total += meshes_[instance.shape].triangle_count();
        return total;
    }
    Aabb<Real> bounds() const { return bounds_; }
    // The indices of both levels, the merged world-space index, and the triangles their leaves
    // test or shading reads (bench/scaling_bench.cpp).
    std::size_t accelerator_bytes() const {
        std::size_t total = top_.memory_bytes();
        for (const auto& mesh : meshes_) total += mesh.accelerator_bytes();
        for (const auto& group : world_meshes_)
            if (group.index) total += group.index->accelerator_bytes();
        return total;
    }
    // How many meshes share one world-space index instead of a top-level entry each.
    std::size_t merged_mesh_count() const {
        std::size_t count = 0;
        for (const auto& group : world_meshes_) count += group.objects.size();
        return count;
    }

    // The radiance object `object` (Hit::object) emits from its surface: a LightMesh's or
    // LightSphere's (and a LightMesh instance's), zero for every other object and for planes.
    Vec3<Real> emitted(std::uint32_t object) const { return object < emitted_.size() ? emitted_[object] : Vec3<Real>(0); }

    // The one closest-hit entry (geometry/ray_batch.hpp): for each active ray, the closest hit in
    // (t_min, t_max], its t_max lowered to it and hits[i] filled; bit i set where rays[i] hits.
    // The batch's culling rule names the surfaces skipped when met from behind
    // (geometry/backface_culling.hpp). Every ray's hit is the one it gets alone, to the bit,
    // however the batch is traversed (closest_many decides): a hit depends on the order in
    // which leaves are visited only when two candidates tie, and a ray whose hit in a lane
    // traversal came at exactly the t_max it was given is traced again on its own.
    // A batch of one is inlined into the caller down to closest_one's dispatch.
    [[gnu::always_inline]] std::uint32_t intersect(const RayBatch<Real>& batch, Hit<Real>* hits) const {
        if (batch.count == 1) {
            if (!(batch.active & 1)) return 0;
            switch (batch.culling) {
                case BackfaceCulling::none: break;
                case BackfaceCulling::triangles: return closest_one<BackfaceCulling::triangles>(batch.rays[0], hits[0]);
                case BackfaceCulling::all: return closest_one<BackfaceCulling::all>(batch.rays[0], hits[0]);
            }
            return closest_one<BackfaceCulling::none>(batch.rays[0], hits[0]);
        }
        return closest_many(batch, hits);
    }

    // The one any-hit entry: bit i set where something lies in (t_min, t_max) of active ray i
    // (open at t_max: a shadow ray aimed at a point on a surface is not blocked by it).
    [[gnu::always_inline]] std::uint32_t occluded(const RayBatch<Real>& batch) const {
        if (batch.count == 1) return (batch.active & 1) && occluded_one(batch.rays[0]);
        return occluded_many(batch);
    }

    // The one rule for how a batch of several rays is traversed, closest and any hits alike:
    // with triangle packets, a scene whose direct form tests its leaves and spheres with a ray
    // in each lane (intersection_batches) takes them so; a scene with an index (no direct form)
    // takes up to index_lanes rays through it together (the nodes' tests of several rays then
    // overlap instead of each waiting on the one before); elsewhere (roots of two leaves or
    // top-level meshes tested directly, no packets) the rays go one by one.
    BatchRoute route() const {
        if constexpr (Mesh::packed) {
            if (intersection_batches()) return BatchRoute::leaf_lanes;
            if (!direct_) return BatchRoute::index_lanes;
        }
        return BatchRoute::ray_by_ray;
    }


private:
    // One ray's closest hit. The small scenes' direct form is a dispatch to two out-of-line
    // functions, and is inlined into the caller; the indexed form stays one out-of-line
    // function. GCC weighed the two as one: once the kernel's slab test changed size it stopped
    // inlining the whole, and every camera ray of the sphere scenes paid a call and its spills
    // (3% of hw1 simple_shading's CPU time, 8-13% of hw1 two_spheres').
    template <BackfaceCulling Culling>
    [[gnu::always_inline]] bool closest_one(Ray<Real>& ray, Hit<Real>& hit) const {
        if (direct_) {
            const bool found = !world_meshes_.empty() && (two_leaves_ ? intersect_world_leaves<Culling, true>(ray, hit)
                                                                       : intersect_world_leaves<Culling, false>(ray, hit));
            return intersect_direct<Culling>(ray, hit, found);
        }
        return intersect_indexed<Culling>(ray, hit);
    }

    // A batch of several rays, traversed as route() says: side by side, the active rays first
    // gathered to the front if the mask has gaps (closest_dense), or ray by ray.
    std::uint32_t closest_many(const RayBatch<Real>& batch, Hit<Real>* hits) const {
        switch (batch.culling) {
            case BackfaceCulling::none: break;
            case BackfaceCulling::triangles: return closest_gathered<BackfaceCulling::triangles>(batch, hits);
            case BackfaceCulling::all: return closest_gathered<BackfaceCulling::all>(batch, hits);
        }
        return closest_gathered<BackfaceCulling::none>(batch, hits);
    }
    template <BackfaceCulling Culling>
    std::uint32_t closest_gathered(const RayBatch<Real>& batch, Hit<Real>* hits) const {
        const BatchRoute way = route();
        if (way == BatchRoute::ray_by_ray) {
            std::uint32_t found = 0;
            for (std::uint32_t lanes = batch.active; lanes != 0; lanes &= lanes - 1) {
                const int i = std::countr_zero(lanes);
                if (closest_one<Culling>(batch.rays[i], hits[i])) found |= std::uint32_t(1) << i;
            }
            return found;
        }
        if (batch.dense()) return closest_dense<Culling>(way, batch.rays, hits, batch.count);
        Gathered gathered(batch);
        Hit<Real> gathered_hits[RayBatch<Real>::max_rays];
        for (int k = 0; k < gathered.count; ++k) gathered_hits[k] = hits[gathered.index[k]];
        const std::uint32_t found = closest_dense<Culling>(way, gathered.rays, gathered_hits, gathered.count);
        for (int k = 0; k < gathered.count; ++k) {
            batch.rays[gathered.index[k]].t_max = gathered.rays[k].t_max;
            hits[gathered.index[k]] = gathered_hits[k];
        }
        return gathered.scatter(found);
    }

    // The any-hit query of one ray.
    [[gnu::always_inline]] bool occluded_one(const Ray<Real>& ray) const {
        if (direct_) return occluded_without_index(ray);
        return occluded_indexed(ray);
    }
    // Several rays, as route() says: side by side, or ray by ray over the active mask.
    std::uint32_t occluded_many(const RayBatch<Real>& batch) const {
        const BatchRoute way = route();
        if (way == BatchRoute::ray_by_ray) {
            std::uint32_t blocked = 0;
            for (std::uint32_t lanes = batch.active; lanes != 0; lanes &= lanes - 1) {
                const int lane = std::countr_zero(lanes);
                if (occluded_one(batch.rays[lane])) blocked |= std::uint32_t(1) << lane;
            }
            return blocked;
        }
        if (batch.dense()) return occluded_dense(way, batch.rays, batch.count);
        Gathered gathered(batch);
        return gathered.scatter(occluded_dense(way, gathered.rays, gathered.count));
    }

    // A batch's active rays gathered to the front, for the side-by-side routes, which take
    // rays[0, count); scatter takes an answer's bits back to the rays' own.
    struct Gathered {
        Ray<Real> rays[RayBatch<Real>::max_rays];
        int index[RayBatch<Real>::max_rays];
        int count = 0;
        explicit Gathered(const RayBatch<Real>& batch) {
            for (std::uint32_t lanes = batch.active; lanes != 0; lanes &= lanes - 1, ++count) {
                index[count] = std::countr_zero(lanes);
                rays[count] = batch.rays[index[count]];
            }
        }
        std::uint32_t scatter(std::uint32_t bits) const {
            std::uint32_t answer = 0;
            for (; bits != 0; bits &= bits - 1) answer |= std::uint32_t(1) << index[std::countr_zero(bits)];
            return answer;
        }
    };

private:
    // intersect through the top-level index (scenes that chose no direct form).
    template <BackfaceCulling Culling>
    bool intersect_indexed(Ray<Real>& ray, Hit<Real>& hit) const {
        const TraversalRay traversal_ray(ray);
        std::optional<TriangleRay> world_triangle_ray;  // made when the ray first enters a mesh
        // The merged world-space meshes first: their hit lowers t_max before the top level
        // tests any box.
        bool found = false;
        std::optional<RayBoxPrecomputed<Real>> box_ray;  // made once, for the first group's box
        for (const WorldMeshes& group : world_meshes_) {
            const Mesh& index = index_of(group);
            const bool cull = culls_back_faces(Culling);
            bool group_hit = false;
            if (group.leaves) {
                if constexpr (Mesh::packed) {
                    group_hit = cull ? intersect_root_leaves<true, true>(index, *group.leaves, ray, world_triangle_ray, hit)
                                     : intersect_root_leaves<false, true>(index, *group.leaves, ray, world_triangle_ray, hit);
                }
            } else {
                if (!enters(index, ray, traversal_ray, box_ray)) continue;
                if (!world_triangle_ray) world_triangle_ray.emplace(ray);
                group_hit = cull ? index.template intersect<true>(ray, traversal_ray, *world_triangle_ray, ray.t_max, hit)
                                 : index.template intersect<false>(ray, traversal_ray, *world_triangle_ray, ray.t_max, hit);
            }
            if (group_hit) {
                if (group.index) group.attribute(index.source_triangle(hit.primitive), hit);
                else hit.object = group.objects[0];
                found = true;
            }
        }
        return intersect_top<Culling>(ray, hit, found, traversal_ray, world_triangle_ray);
    }

public:
    // Planes are unbounded, so no index holds them: every ray tests each one (closest hit, as
    // intersect above), eight at a time (plane_distances); the lanes are then accepted in order
    // as one plane after another would be, so the hit is the scalar loop's.
    template <BackfaceCulling Culling = BackfaceCulling::none>
    bool intersect_planes(Ray<Real>& ray, Hit<Real>& hit) const {
        bool found = false;
        for (std::size_t b = 0; b < plane_blocks_.size(); ++b) {
            alignas(64) Real t[direct_width];
            alignas(64) Real denominator[direct_width];
            for (std::uint32_t lanes = plane_distances(plane_blocks_[b], ray, t, denominator); lanes != 0; lanes &= lanes - 1) {
                const int lane = std::countr_zero(lanes);
                if (!(t[lane] <= ray.t_max)) continue;
                if constexpr (Culling == BackfaceCulling::all) {
                    if (denominator[lane] > 0) continue;
                }
                ray.t_max = t[lane];
                hit = Hit<Real>{t[lane], std::uint32_t(instances_.size() + b * direct_width + std::size_t(lane)), 0, 0, 0};
                found = true;
            }
        }
        return found;
    }

private:
    // occluded_one in a scene with an index (no direct form).
    bool occluded_indexed(const Ray<Real>& ray) const {
        const TraversalRay traversal_ray(ray);
        std::optional<TriangleRay> world_triangle_ray;
        std::optional<RayBoxPrecomputed<Real>> box_ray;
        for (const WorldMeshes& group : world_meshes_) {
            const Mesh& index = index_of(group);
            if (!enters(index, ray, traversal_ray, box_ray)) continue;
            if (!world_triangle_ray) world_triangle_ray.emplace(ray);
            if (index.occluded(ray, traversal_ray, *world_triangle_ray, ray.t_max)) return true;
        }
        if (direct_top_) return occluded_direct(ray);
        const auto& order = top_.primitive_indices();
        const bool blocked =
            !top_objects_.empty() &&
            top_.traverse_any(traversal_ray, ray.t_min, ray.t_max, [&](std::uint32_t first, std::uint32_t count, Real& t_max) {
                for (std::uint32_t i = first; i < first + count; ++i)
                    if (occludes(instances_[top_objects_[order[i]]], ray, traversal_ray, world_triangle_ray, t_max))
                        return true;
                return false;
            });
        return blocked || occluded_by_planes(ray);
    }

    // Whether closest_dense tests its rays side by side: scenes without an index (direct_)
    // whose world-space meshes, if any, are each one leaf, under the packed watertight test,
    // and whose top level holds no mesh. The camera rays of hw1's small scenes (a floor of two
    // triangles under spheres, spheres alone) are such rays. A root of two leaves keeps
    // intersect's own tie rule (intersect_root_leaves); a top-level mesh (a transformed plate)
    // needs each ray's may_hit for its lane, which the spheres' lanes would only repeat (hw2
    // simple_transform, two rotated meshes and a sphere: 1.04 of the CPU time with them).
    bool intersection_batches() const {
        if constexpr (Mesh::packed) {
            if constexpr (Mesh::Packets::tests_ray_lanes) return direct_ && !two_leaves_ && direct_meshes_.empty();
        }
        return false;
    }

    // The closest hits of rays[0, count) side by side, each as closest_one gives it alone: its
    // ray.t_max lowered to the hit and hits[i] filled, bit i of the answer set, where it hits
    // (count <= 32). BatchRoute::leaf_lanes: the world meshes' leaves are tested against several
    // rays at once (TriangleMesh::intersect_leaf_lanes, lane by lane the leaf test's bits),
    // group after group as closest_one takes them, then the direct spheres likewise
    // (intersect_direct_spheres_lanes), each ray then the planes on its own.
    // BatchRoute::index_lanes: the rays traverse the index together (intersect_through_index).
    template <BackfaceCulling Culling>
    std::uint32_t closest_dense(BatchRoute way, Ray<Real>* rays, Hit<Real>* hits, int count) const {
        std::uint32_t found = 0;
        if (way == BatchRoute::index_lanes) {
            if constexpr (Mesh::packed) {
                for (int first = 0; first < count; first += index_lanes)
                    found |= intersect_through_index<Culling>(rays + first, hits + first, std::min(index_lanes, count - first))
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
                    std::uint32_t world_hits = 0;
                    for (const WorldMeshes& mesh_group : world_meshes_) {
                        const typename Mesh::Leaf& leaf = mesh_group.leaves->leaf[0];
                        const std::uint32_t lanes = lanes_reaching(leaf, group, n, 0);
                        if (lanes == 0) continue;
                        if (!lanes_ray) lanes_ray.emplace(group, n);
                        typename Packets::LaneHits lane_hits;
                        lane_hits.t_max = lanes_t_max<Packets>(group, n);
                        const Mesh& index = index_of(mesh_group);
                        if (culls_back_faces(Culling))
                            index.template intersect_leaf_lanes<true>(*lanes_ray, leaf, lanes, lane_hits);
                        else
                            index.template intersect_leaf_lanes<false>(*lanes_ray, leaf, lanes, lane_hits);
                        std::uint32_t taken = lane_hits.found & lanes;
                        if (taken == 0) continue;
                        alignas(64) Real t[width], b1[width], b2[width];
                        lane_hits.t_max.store(t);
                        lane_hits.b1.store(b1);
                        lane_hits.b2.store(b2);
                        for (; taken != 0; taken &= taken - 1) {
                            const int i = std::countr_zero(taken);
                            Hit<Real>& hit = group_hits[i];
                            group[i].t_max = t[i];
                            hit.t = t[i];
                            hit.primitive = lane_hits.slot[std::size_t(i)];
                            hit.b1 = b1[i];
                            hit.b2 = b2[i];
                            if (mesh_group.index) mesh_group.attribute(index.source_triangle(hit.primitive), hit);
                            else hit.object = mesh_group.objects[0];
                            world_hits |= std::uint32_t(1) << i;
                        }
                    }
                    static_assert(width <= direct_width, "a group of rays fits the direct lanes");
                    if (!direct_spheres_.empty()) intersect_direct_spheres_lanes(group, group_hits, n, world_hits);
                    // No direct meshes (intersection_batches): the planes, ray by ray, where there are any.
                    if (plane_blocks_.empty()) {
                        found |= world_hits << first;
                        continue;
                    }
                    for (int i = 0; i < n; ++i)
                        if (intersect_direct_meshes<Culling>(group[i], group_hits[i], 0, (world_hits >> i) & 1))
                            found |= std::uint32_t(1) << (first + i);
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
    std::uint32_t occluded_dense(BatchRoute way, const Ray<Real>* rays, int count) const {
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
                    for (const WorldMeshes& mesh_group : world_meshes_) {
                        const typename Mesh::Leaf& leaf = mesh_group.leaves->leaf[0];
                        const std::uint32_t lanes = lanes_reaching(leaf, group, n, found);
                        if (lanes == 0) continue;
                        if (!lanes_ray) {
                            lanes_ray.emplace(group, n);
                            t_max = lanes_t_max<Packets>(group, n);
                        }
                        found |= index_of(mesh_group).occluded_leaf_lanes(*lanes_ray, leaf, lanes, *t_max);
                    }
                    if (found != present && !direct_spheres_.empty())
                        intersect_direct_spheres_lanes<true>(group, nullptr, n, found);
                    // No direct meshes (intersection_batches): the planes, ray by ray, where there are any.
                    if (plane_blocks_.empty()) {
                        blocked |= found << first;
                        continue;
                    }
                    for (int i = 0; i < n; ++i)
                        if (((found >> i) & 1) || occluded_by_planes(group[i])) blocked |= std::uint32_t(1) << (first + i);
                }
            }
        }
        return blocked;
    }

public:
    bool occluded_by_planes(const Ray<Real>& ray) const {
        for (const PlaneBlock& block : plane_blocks_) {
            alignas(64) Real t[direct_width];
            alignas(64) Real denominator[direct_width];
            for (std::uint32_t lanes = plane_distances(block, ray, t, denominator); lanes != 0; lanes &= lanes - 1)
                if (t[std::countr_zero(lanes)] < ray.t_max) return true;
        }
        return false;
    }

    // One primitive of one object, tested as intersect tests it (world-space ray, the
    // policy's triangle test, the sphere test): for an index other than the policy's own (an
    // Embree scene, accel/embree.hpp) that finds the primitive but leaves prism to compute the
    // hit. `primitive` is a triangle's position in its mesh (identity order under BruteForce);
    // spheres ignore it. On a hit in (t_min, t_max] it lowers ray.t_max and fills hit.
    bool intersect_primitive(std::uint32_t object, std::uint32_t primitive, Ray<Real>& ray, Hit<Real>& hit) const {
        const Instance& instance = instances_[object];
        const Ray<Real> local = to_object(instance, ray);
        bool found;
        if (instance.kind == Kind::mesh) {
            found = meshes_[instance.shape].intersect_triangle(primitive, local, ray.t_max, hit);
        } else {
            Real t;
            found = spheres_[instance.shape].intersect(local, ray.t_min, ray.t_max, t);
            if (found) {
                ray.t_max = t;
                hit = Hit<Real>{t, object, 0, 0, 0};
            }
        }
        if (found) hit.object = object;
        return found;
    }

    // What an outside index needs to mirror the objects: whether object i is a sphere, and the
    // world box intersect's own index holds for it (covering a moving object's sweep).
    bool is_sphere(std::uint32_t object) const { return instances_[object].kind == Kind::sphere; }
    // Whether `culling` skips this triangle of this object for this (world-space) ray, decided
    // as intersect decides it.
    bool culled(std::uint32_t object, std::uint32_t primitive, const Ray<Real>& ray, BackfaceCulling culling) const {
        if (!culls(object, culling)) return false;
        const Instance& instance = instances_[object];
        return meshes_[instance.shape].faces_away(primitive, to_object(instance, ray).direction);
    }
    // Whether camera rays skip object's back-facing triangles under `culling`, as intersect does.
    bool culls(std::uint32_t object, BackfaceCulling culling) const {
        const Instance& instance = instances_[object];
        return instance.kind == Kind::mesh && culls_back_faces(culling);
    }
    // The rule itself for a mesh's triangles, whatever their shading (geometry/backface_culling.hpp).
    static constexpr bool culls_back_faces(BackfaceCulling culling) { return culling != BackfaceCulling::none; }
    Aabb<Real> world_bounds(std::uint32_t object) const { return instances_[object].world_bounds; }

    // Two parts are left out for callers that never read them. `Parametrised` false leaves a
    // sphere's (u, v) and tangents zero: renderers compiled without textures never read them,
    // and the sphere's acos, atan2 and sincos were 6-8% of a mirror sphere scene's time (hw1
    // mirror_spheres); meshes fill theirs as before. `spawn_point` false leaves object_point and
    // object_error zero, which only spawn_origin reads: rays that leave by the scene's epsilon
    // (45 of the 57 hw1-hw2 course scenes) never call it, and a triangle's spawn point (its
    // error bound, in double) was 5% of a small scene's time.
    // The renderers without textures (Parametrised false: hw1's scenes) have it inlined into
    // their trace, where the fields they never read (tangents, texture frame and positions) are
    // not stored at all; out of line it was a call per hit and a 200-byte record written whole.
    template <bool Parametrised = true>
        requires(Parametrised)
    SurfacePoint<Real> surface(const Ray<Real>& ray, const Hit<Real>& hit, bool spawn_point = true) const {
        return surface_of<true>(ray, hit, spawn_point);
    }
    template <bool Parametrised>
        requires(!Parametrised)
    [[gnu::always_inline]] SurfacePoint<Real> surface(const Ray<Real>& ray, const Hit<Real>& hit,
                                                      bool spawn_point = true) const {
        return surface_of<false>(ray, hit, spawn_point);
    }

private:
    template <bool Parametrised>
    [[gnu::always_inline]] SurfacePoint<Real> surface_of(const Ray<Real>& ray, const Hit<Real>& hit,
                                                         bool spawn_point) const {
        SurfacePoint<Real> point;
        point.position = ray.at(hit.t);
        point.object = hit.object;
        point.time = ray.time;
        if (hit.object >= instances_.size()) {
            const std::size_t p = hit.object - instances_.size();
            point.geometric_normal = point.shading_normal = point.object_normal = planes_[p].normal;
            point.texture_position = point.position;
            if (spawn_point) {
                const PointWithError<Real> exact = planes_[p].hit_point(point.position);
                point.object_point = exact.point;
                point.object_error = exact.error;
            }
            point.local_position = point.position;
            point.material = plane_materials_[p];
            point.textures = texture_lists_[plane_textures_[p]];
            return point;
        }
        const Instance& instance = instances_[hit.object];
        point.material = instance.material;
        point.textures = texture_lists_[instance.textures];
        const Vec3<Real> unmoved = point.position - displacement(instance, ray.time);
        point.local_position = instance.transformed ? instance.to_object(unmoved) : unmoved;
        Vec3<Real> geometric_normal, shading_normal;
        PointWithError<Real> exact;
        if (instance.kind == Kind::mesh) {
            const auto& mesh = meshes_[instance.shape];
            mesh.surface(hit, geometric_normal, shading_normal, point.uv, point.dpdu, point.dpdv);
            if (spawn_point) exact = mesh.spawn_point(hit);
        } else {
            const SphereShape<Real>& sphere = spheres_[instance.shape];
            geometric_normal = shading_normal = glm::normalize(point.local_position - sphere.center);
            if constexpr (Parametrised) sphere.parametrise(point.local_position, point.uv, point.dpdu, point.dpdv);
            if (spawn_point) exact = sphere_hit_point(sphere.center, sphere.radius, point.local_position);
        }
        point.object_point = exact.point;
        point.object_error = exact.error;
        point.object_normal = geometric_normal;
        // Textures on a mesh live in its object space, on a sphere in world space (hit.hpp).
        if (instance.kind == Kind::mesh) {
            point.texture_position = point.local_position;
            if (instance.transformed) point.texture_frame = instance.object_to_world_linear;
        } else {
            point.texture_position = point.position;
        }
        if (instance.transformed) {
            // Spheres and flat meshes shade with the geometric normal itself (the same bits):
            // it is mapped and normalised once.
            const bool one_normal = std::memcmp(&geometric_normal, &shading_normal, sizeof(geometric_normal)) == 0;
            geometric_normal = glm::normalize(transform_normal(instance.normal_to_world, geometric_normal));
            shading_normal = one_normal ? geometric_normal
                                        : glm::normalize(transform_normal(instance.normal_to_world, shading_normal));
            // Tangents are directions on the surface: they map by the linear part itself. An
            // unparametrised sphere has none (zero, and read by nothing).
            if (Parametrised || instance.kind == Kind::mesh) {
                point.dpdu = transform_direction(instance.object_to_world_linear, point.dpdu);
                point.dpdv = transform_direction(instance.object_to_world_linear, point.dpdv);
            }
        }
        point.geometric_normal = geometric_normal;
        point.shading_normal = shading_normal;
        return point;
    }

public:
    // The origin of a ray leaving `point` (from surface()) towards `direction`: the exact hit
    // point pushed past its error bound along the geometric normal, to the side the ray leaves
    // by, so the ray cannot find the surface it left again, at any scale and in float or double.
    Vec3<Real> spawn_origin(const SurfacePoint<Real>& point, const Vec3<Real>& direction) const {
        const PointWithError<Real> exact{point.object_point, point.object_error};
        if (point.object >= instances_.size()) return offset_ray_origin(exact, point.object_normal, direction);
        const Instance& instance = instances_[point.object];
        Vec3<Real> origin = instance.transformed
                                ? offset_ray_origin(transforms_[instance.transform], exact, point.object_normal, direction)
                                : offset_ray_origin(exact, point.object_normal, direction);
        if constexpr (MotionBlur) {
            if (instance.moving) {
                // Moving the origin by m t rounds once more, by at most u (|origin| + |m t|) per
                // axis: clear that along the world normal too.
                const Vec3<Real> shift = instance.motion * point.time;
                origin += shift;
                origin = offset_ray_origin(origin, gamma<Real>(2) * (abs_each(origin) + abs_each(shift)),
                                           point.geometric_normal, direction);
            }
        }
        return origin;
    }

    // spawn_origin's answer depends on the direction only through the side of the surface the
    // ray leaves by, as each offset_ray_origin it calls decides it (in object space for an
    // instance with a transformation; the world normal's side too for a moving one): 0 to 3.
    // Rays that leave one point by the same side start from the same origin, so the shadow rays
    // to every light can share one (the error-bounded origin of an instance was a third of
    // hw2 metal_glass_plates' time, computed again for each of its lights).
    [[gnu::always_inline]] int spawn_side(const SurfacePoint<Real>& point, const Vec3<Real>& direction) const {
        if (point.object >= instances_.size()) return glm::dot(direction, point.object_normal) < 0;
        const Instance& instance = instances_[point.object];
        int side = instance.transformed
                       ? glm::dot(transform_direction(transforms_[instance.transform].world_to_object, direction),
                                  point.object_normal) < 0
                       : glm::dot(direction, point.object_normal) < 0;
        if constexpr (MotionBlur) {
            if (instance.moving) side += 2 * (glm::dot(direction, point.geometric_normal) < 0);
        }
        return side;
    }

private:
    enum class Kind : std::uint8_t { mesh, sphere };
    using Mesh = TriangleMesh<Real, Policy>;
    // The top level and every mesh share one index type, so one prepared ray serves both.
    using TraversalRay = typename Index::TraversalRay;
    using TriangleRay = typename Mesh::TriangleRay;

    struct Instance {
        Kind kind = Kind::mesh;
        bool transformed = false;
        std::uint32_t shape = 0;
        std::uint32_t material = 0;
        Mat4<Real> world_to_object{1};
        Mat3<Real> world_to_object_linear{1};
        Mat3<Real> normal_to_world{1};
        Mat3<Real> object_to_world_linear{1};
        std::uint32_t textures = 0;   // index into texture_lists_
        std::uint32_t transform = 0;  // index into transforms_, when transformed
        bool moving = false;
        Vec3<Real> motion{0};
        Aabb<Real> world_bounds;

        // Forced inline: the direct spheres' test calls it for every ray a transformed sphere may
        // meet, and GCC left it out of line there (8% of hw2 spheres.json).
        [[gnu::always_inline]] Vec3<Real> to_object(const Vec3<Real>& p) const { return transform_point(world_to_object, p); }
        // The direction is transformed but not renormalised, so t means the same in both spaces.
        [[gnu::always_inline]] Ray<Real> to_object(const Ray<Real>& ray) const {
            return {to_object(ray.origin), transform_direction(world_to_object_linear, ray.direction), ray.t_min, ray.t_max,
                    ray.time};
        }
    };

    // The meshes that share the world's space at every instant (no transformation, not
    // moving) go into one index over all their triangles, as Embree builds one BVH over a
    // scene's geometries: a ray then enters one tree instead of each overlapping mesh's tree
    // from the top level. A mesh that a MeshInstance places keeps its own index for the
    // instance to use. Brute force (PrimitiveList) has no levels to save, and Embree's shapes
    // (accel/embree.hpp) keep one mesh per object.
    static std::vector<bool> merged_meshes(const scene::Scene& scene) {
        std::vector<bool> merged(scene.meshes.size(), false);
        if constexpr (std::is_same_v<Index, PrimitiveList<Real>>) return merged;
        std::vector<bool> instanced(scene.meshes.size(), false);
        for (const auto& instance : scene.mesh_instances) instanced[instance.base_mesh] = true;
        for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
            const scene::Mesh& mesh = scene.meshes[m];
            merged[m] = !instanced[m] && mesh.transform == glm::dmat4(1.0) && (!MotionBlur || mesh.motion == glm::dvec3(0.0));
        }
        return merged;
    }

    void add_instance(Kind kind, std::uint32_t shape, std::size_t material, const glm::dmat4& transform,
                      const Aabb<Real>& object_bounds, const std::vector<std::size_t>& textures,
                      const glm::dvec3& motion) {
        Instance instance;
        instance.textures = add_texture_list(textures);
        instance.kind = kind;
        instance.shape = shape;
        instance.material = std::uint32_t(material);
        instance.transformed = transform != glm::dmat4(1.0);
        if (instance.transformed) {
            // Inverses are taken in double from the file's values, then rounded once to Real.
            const glm::dmat4 inverse = glm::inverse(transform);
            instance.world_to_object = Mat4<Real>(inverse);
            instance.world_to_object_linear = Mat3<Real>(glm::dmat3(inverse));
            instance.normal_to_world = Mat3<Real>(glm::transpose(glm::dmat3(inverse)));
            instance.object_to_world_linear = Mat3<Real>(glm::dmat3(transform));
            instance.transform = std::uint32_t(transforms_.size());
            transforms_.emplace_back(transform);
            for (int c = 0; c < 8; ++c)
                instance.world_bounds.extend(
                    Vec3<Real>(transform * glm::dvec4(glm::dvec3(object_bounds.corner(c)), 1.0)));
            // The corners are rounded to nearest, so the box could fall inside the transformed
            // object by half an ulp: rays through a silhouette vertex on it were lost (found by
            // the direct test of test_small_scenes). One ulp outwards keeps it conservative.
            for (int axis = 0; axis < 3; ++axis) {
                instance.world_bounds.min[axis] = next_down(instance.world_bounds.min[axis]);
                instance.world_bounds.max[axis] = next_up(instance.world_bounds.max[axis]);
            }
        } else {
            instance.world_bounds = object_bounds;
        }
        if (MotionBlur && motion != glm::dvec3(0.0)) {
            instance.moving = true;
            instance.motion = Vec3<Real>(motion);
            Aabb<Real> swept = instance.world_bounds;
            swept.extend(Aabb<Real>{swept.min + instance.motion, swept.max + instance.motion});
            // The sweep's corners are rounded sums: one ulp outwards keeps the box conservative.
            for (int axis = 0; axis < 3; ++axis) {
                swept.min[axis] = next_down(swept.min[axis]);
                swept.max[axis] = next_up(swept.max[axis]);
            }
            instance.world_bounds = swept;
        }
        instances_.push_back(instance);
    }

    std::uint32_t add_texture_list(const std::vector<std::size_t>& textures) {
        if (textures.empty()) return 0;
        texture_lists_.emplace_back(textures.begin(), textures.end());
        return std::uint32_t(texture_lists_.size() - 1);
    }

    // Where a moving instance has gone by the instant `time`; zero without motion blur.
    Vec3<Real> displacement(const Instance& instance, Real time) const {
        if constexpr (MotionBlur) {
            if (instance.moving) return instance.motion * time;
        }
        return Vec3<Real>(0);
    }

    // The ray in the instance's object space, at the ray's instant for moving instances.
    // Forced inline as Instance::to_object is (the top level's leaf and the direct meshes call it).
    [[gnu::always_inline]] Ray<Real> to_object(const Instance& instance, const Ray<Real>& ray) const {
        if constexpr (MotionBlur) {
            if (instance.moving) {
                Ray<Real> unmoved = ray;
                unmoved.origin -= instance.motion * ray.time;
                return instance.transformed ? instance.to_object(unmoved) : unmoved;
            }
        }
        return instance.transformed ? instance.to_object(ray) : ray;
    }

    // intersect_indexed past the world meshes: the top level (direct or through its index),
    // then the planes; `found` whether the world meshes were hit.
    template <BackfaceCulling Culling>
    [[gnu::always_inline]] bool intersect_top(Ray<Real>& ray, Hit<Real>& hit, bool found, const TraversalRay& traversal_ray,
                                              std::optional<TriangleRay>& world_triangle_ray) const {
        if (direct_top_) return intersect_direct<Culling>(ray, hit, found);
        if (top_objects_.empty()) return intersect_planes<Culling>(ray, hit) || found;
        const auto& order = top_.primitive_indices();
        top_.traverse_closest(traversal_ray, ray.t_min, ray.t_max, [&](std::uint32_t first, std::uint32_t count, Real& t_max) {
            bool leaf_hit = false;
            for (std::uint32_t i = first; i < first + count; ++i) {
                const std::uint32_t object = top_objects_[order[i]];
                if (intersect_instance<Culling>(instances_[object], ray, traversal_ray, world_triangle_ray, t_max, hit)) {
                    hit.object = object;
                    leaf_hit = true;
                }
            }
            found |= leaf_hit;
            return leaf_hit;
        });
        return intersect_planes<Culling>(ray, hit) || found;
    }

    // closest_dense in a scene traversed through its index (no direct form), for up to
    // index_lanes rays: each world mesh's closest hits for the rays together
    // (TriangleMesh::intersect_lanes: each ray set up and tested as intersect_indexed sets it up
    // and tests it, the leaves visited in one order for all), then each ray's top level and
    // planes on its own (intersect_top). A pixel's camera rays reach the same nodes, whose
    // tests then overlap instead of each waiting on the one before. A ray whose hit in a mesh
    // may depend on that order (a tie) is traced through that mesh again on its own, from
    // where it was before the mesh, so every ray's hit is intersect's.
    template <BackfaceCulling Culling>
    std::uint32_t intersect_through_index(Ray<Real>* rays, Hit<Real>* hits, int count) const
        requires Mesh::packed
    {
        const std::uint32_t present = (std::uint32_t(1) << count) - 1;
        WorldSpaceRays world(rays, count);
        Real* const t_min = world.t_min;
        Real* const t_max = world.t_max;
        auto& traversal = world.traversal;
        std::uint32_t found = 0;
        for (const WorldMeshes& group : world_meshes_) {
            const Mesh& index = index_of(group);
            const bool cull = culls_back_faces(Culling);
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
                cull ? index.template intersect_lanes<true>(rays, traversal.data(), world_triangle, t_min, t_max, lanes, hits,
                                                            tied)
                     : index.template intersect_lanes<false>(rays, traversal.data(), world_triangle, t_min, t_max, lanes, hits,
                                                             tied);
            for (; tied != 0; tied &= tied - 1) {
                const int i = std::countr_zero(tied);
                const std::uint32_t bit = std::uint32_t(1) << i;
                t_max[i] = t_before[std::size_t(i)];
                hits[i] = hit_before[std::size_t(i)];
                rays[i].t_max = t_max[i];
                const bool hit = cull ? index.template intersect<true>(rays[i], traversal[std::size_t(i)], world_triangle[i],
                                                                       t_max[i], hits[i])
                                      : index.template intersect<false>(rays[i], traversal[std::size_t(i)],
                                                                        world_triangle[i], t_max[i], hits[i]);
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
        if (direct_top_ || top_objects_.empty()) {
            for (int i = 0; i < count; ++i) {
                rays[i].t_max = t_max[i];
                // Made again where a top-level mesh in world space needs it (its set-up is the
                // ray's alone, so the same bits).
                std::optional<TriangleRay> world_triangle_ray;
                if (intersect_top<Culling>(rays[i], hits[i], (found >> i) & 1, traversal[std::size_t(i)], world_triangle_ray))
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
                    const Instance& instance = instances_[object];
                    std::uint32_t instance_hits = 0;
                    if (instance.kind == Kind::mesh && in_world_space(instance)) {
                        const TriangleRay* const world_triangle = world.triangles(testing);
                        const Mesh& mesh = meshes_[instance.shape];
                        instance_hits = culls_back_faces(Culling)
                                            ? mesh.template intersect_lanes<true>(rays, traversal.data(), world_triangle, t_min,
                                                                                  t_max, testing, hits, tied)
                                            : mesh.template intersect_lanes<false>(rays, traversal.data(), world_triangle, t_min,
                                                                                   t_max, testing, hits, tied);
                    } else {
                        instance_hits = intersect_in_object_space<Culling>(instance, rays, t_min, t_max, testing, hits, tied);
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
                if (intersect_top<Culling>(rays[i], hits[i], (world_found & bit) != 0, traversal[std::size_t(i)],
                                           world_triangle_ray))
                    answer |= bit;
                continue;
            }
            rays[i].t_max = t_max[i];
            if (intersect_planes<Culling>(rays[i], hits[i]) || (found & bit)) answer |= bit;
        }
        return answer;
    }

    // intersect_instance for the rays of `lanes` and an object not in world space: each ray
    // taken to its object space and set up there as intersect_instance does; `tied` as
    // TriangleMesh::intersect_lanes sets it (a sphere's hit at the t_max it was given, too).
    template <BackfaceCulling Culling>
    std::uint32_t intersect_in_object_space(const Instance& instance, const Ray<Real>* rays, const Real* t_min, Real* t_max,
                                            std::uint32_t lanes, Hit<Real>* hits, std::uint32_t& tied) const
        requires Mesh::packed
    {
        std::uint32_t hit = 0;
        if (instance.kind != Kind::mesh) {
            for (; lanes != 0; lanes &= lanes - 1) {
                const int i = std::countr_zero(lanes);
                Real t;
                if (!spheres_[instance.shape].intersect(to_object(instance, rays[i]), rays[i].t_min, t_max[i], t)) continue;
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
        local.make(*this, instance, rays, lanes);
        const Mesh& mesh = meshes_[instance.shape];
        return culls_back_faces(Culling)
                   ? mesh.template intersect_lanes<true>(local.ray.data(), local.traversal.data(), local.triangle.data(),
                                                         t_min, t_max, lanes, hits, tied)
                   : mesh.template intersect_lanes<false>(local.ray.data(), local.traversal.data(), local.triangle.data(),
                                                          t_min, t_max, lanes, hits, tied);
    }

    // occluded_dense in a scene traversed through its index (no direct form), for up to
    // index_lanes rays: every level's any hits found for the rays together, each ray set up and
    // tested as occluded sets it up and tests it (WideBvhTree::traverse_any_lanes), so each
    // ray's answer is occluded's. A row's shadow rays to one light reach the same nodes, whose
    // tests then overlap instead of each waiting on the one before (hw2 horse_instanced's
    // three instanced horses: the shadow rays were a third of its time).
    static constexpr int index_lanes = 16;
    std::uint32_t occluded_through_index(const Ray<Real>* rays, int count) const
        requires Mesh::packed
    {
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
        if (direct_top_) {
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
                        const Instance& instance = instances_[top_objects_[order[k]]];
                        const std::uint32_t lanes = testing & ~hit;
                        if (instance.kind == Kind::mesh && in_world_space(instance)) {
                            hit |= meshes_[instance.shape].occluded_lanes(rays, traversal.data(), world.triangles(lanes),
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
            if (occluded_by_planes(rays[i])) blocked |= std::uint32_t(1) << i;
        }
        return blocked;
    }

    // The rays of `lanes` taken to an instance's object space and set up there, each as
    // occludes and intersect_instance set up one (occludes_in_object_space,
    // intersect_in_object_space).
    struct ObjectSpaceRays {
        Unconstructed<Ray<Real>, index_lanes> ray;
        Unconstructed<TraversalRay, index_lanes> traversal;
        Unconstructed<TriangleRay, index_lanes> triangle;

        void make(const SceneGeometry& geometry, const Instance& instance, const Ray<Real>* rays, std::uint32_t lanes) {
            for (; lanes != 0; lanes &= lanes - 1) {
                const std::size_t i = std::size_t(std::countr_zero(lanes));
                const Ray<Real>& local = ray.make(i, geometry.to_object(instance, rays[i]));
                traversal.make(i, local);
                triangle.make(i, local);
            }
        }
    };

    // The world-space set-up of up to index_lanes rays, each as intersect and occluded make it
    // for one: its traversal set-up and its t range, and its triangle set-up once it first
    // enters a world-space mesh (triangles).
    struct WorldSpaceRays {
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

    // occludes for the rays of `lanes` and an object not in world space: each ray taken to
    // its object space and set up there as occludes does.
    std::uint32_t occludes_in_object_space(const Instance& instance, const Ray<Real>* rays, const Real* t_min,
                                           const Real* t_max, std::uint32_t lanes) const
        requires Mesh::packed
    {
        std::uint32_t blocked = 0;
        if (instance.kind != Kind::mesh) {
            for (; lanes != 0; lanes &= lanes - 1) {
                const int i = std::countr_zero(lanes);
                Real t;
                if (spheres_[instance.shape].intersect(to_object(instance, rays[i]), t_min[i], t_max[i], t) && t < t_max[i])
                    blocked |= std::uint32_t(1) << i;
            }
            return blocked;
        }
        ObjectSpaceRays local;
        local.make(*this, instance, rays, lanes);
        return meshes_[instance.shape].occluded_lanes(local.ray.data(), local.traversal.data(), local.triangle.data(), t_min,
                                                      t_max, lanes);
    }

    // Whether the ray meets the box of a world-space index within its interval, by the same
    // conservative slab test as the BVHs (Ize's widened exit): the triangle set-up is then made
    // before the index is entered (eagerly, outside the kernel's leaf loop) and only for rays
    // that may reach a leaf, as the top level's box test did for a mesh in it.
    // A wide BVH tests its root's children with the traversal ray instead (WideBvhTree::enters):
    // no division of its own, and rays between the children's boxes are stopped too.
    static bool enters(const Mesh& index, const Ray<Real>& ray, const TraversalRay& traversal_ray,
                       std::optional<RayBoxPrecomputed<Real>>& box_ray) {
        if constexpr (requires { index.enters(traversal_ray, ray.t_min, ray.t_max); }) {
            return index.enters(traversal_ray, ray.t_min, ray.t_max);
        } else {
            if (!box_ray) box_ray.emplace(ray);
            return intersect_box(index.bounds(), *box_ray, ray.t_min, ray.t_max, robust_far_scale<Real>) != infinity<Real>;
        }
    }

    // Whether the instance's object space is the world's at every instant: then its mesh
    // reuses the world ray's set-up (the same ray, bit for bit) instead of preparing its own.
    static bool in_world_space(const Instance& instance) {
        if constexpr (MotionBlur) {
            if (instance.moving) return false;
        }
        return !instance.transformed;
    }

    // Forced inline, as occludes below: the top level's leaf callbacks call them for every
    // object they reach, and with to_object forced inline GCC put both out of line (nm).
    template <BackfaceCulling Culling>
    [[gnu::always_inline]] bool intersect_instance(const Instance& instance, const Ray<Real>& ray,
                                                   const TraversalRay& traversal_ray,
                                                   std::optional<TriangleRay>& world_triangle_ray, Real& t_max,
                                                   Hit<Real>& hit) const {
        if (instance.kind == Kind::mesh) {
            const auto& mesh = meshes_[instance.shape];
            const bool cull = culls_back_faces(Culling);
            if (in_world_space(instance)) {
                if (!world_triangle_ray) world_triangle_ray.emplace(ray);
                return cull ? mesh.template intersect<true>(ray, traversal_ray, *world_triangle_ray, t_max, hit)
                            : mesh.template intersect<false>(ray, traversal_ray, *world_triangle_ray, t_max, hit);
            }
            const Ray<Real> local = to_object(instance, ray);
            return cull ? mesh.template intersect<true>(local, t_max, hit) : mesh.template intersect<false>(local, t_max, hit);
        }
        const Ray<Real> local = to_object(instance, ray);
        Real t;
        if (!spheres_[instance.shape].intersect(local, ray.t_min, t_max, t)) return false;
        t_max = t;
        // The whole record, barycentrics too: what a hit leaves is then the same whichever
        // hits it replaced (intersect_through_index takes them in another order).
        hit.t = t;
        hit.primitive = 0;
        hit.b1 = hit.b2 = 0;
        return true;
    }

    [[gnu::always_inline]] bool occludes(const Instance& instance, const Ray<Real>& ray, const TraversalRay& traversal_ray,
                  std::optional<TriangleRay>& world_triangle_ray, Real t_max) const {
        if (instance.kind == Kind::mesh && in_world_space(instance)) {
            if (!world_triangle_ray) world_triangle_ray.emplace(ray);
            return meshes_[instance.shape].occluded(ray, traversal_ray, *world_triangle_ray, t_max);
        }
        const Ray<Real> local = to_object(instance, ray);
        if (instance.kind == Kind::mesh) return meshes_[instance.shape].occluded(local, t_max);
        Real t;
        return spheres_[instance.shape].intersect(local, ray.t_min, t_max, t) && t < t_max;
    }

    // A top level of a few spheres and nothing else (the course's sphere scenes of 1 to 8) is
    // tested sphere after sphere, without the index: the traversal's prepared ray (three
    // divisions, broadcast) and its node test cost more than the spheres (hw2 mirror_room: the
    // prepared ray alone was 15% of the time). Each sphere is tested as the index's leaf tests
    // it, so the hits are the same; only two spheres hit at exactly the same distance could
    // resolve otherwise (the later one tested wins in both).
    // Up to 8, the spheres' culls in one SIMD pass (may_hit): tested one by one, 5 and 6
    // untransformed spheres (hw1 spheres_with_plane, spheres.json) had cost more than the
    // index's one 8-wide box test (1.04-1.05 of its CPU time, whole3).
    static constexpr int direct_width = 8;
    static constexpr std::size_t direct_limit = direct_width;
    using DirectPack = simd::Pack<Real, direct_width>;
    // Each direct object on cache lines of its own (alignas(64), so the vector's block is too):
    // with the small heap block next to data the render threads write, hw2 simple_reflectance's
    // shadow rays stalled on reading it at 2 threads (1.25 of base's CPU time, 0.91 at 1 thread).
    struct alignas(64) DirectSphere {
        std::uint32_t object = 0;
        // How the ray reaches object space: unchanged, moved by `translation` (a transform that
        // only translates: the matrix product's answer, ox + tx with zero terms, bit for bit),
        // or by the instance's matrix.
        enum class Map : std::uint8_t { none, translation, matrix } map = Map::none;
        Vec3<Real> translation{0};
    };
    // Up to eight planes SoA, for one SIMD pass of PlaneShape::intersect's arithmetic.
    struct PlaneBlock {
        alignas(64) Real point[3][direct_width] = {};
        alignas(64) Real normal[3][direct_width] = {};
        std::uint32_t lanes = 0;  // the planes present
    };

    // PlaneShape::intersect for a block's planes, lane by lane with its operations in its order
    // (the dot products as glm sums them): bit i set where plane i is met in (t_min, ...) with a
    // t that t_max has not yet been compared with; t and the denominator (direction . normal)
    // stored. The scalar test's shortcut for planes behind the ray only skips a division whose
    // t would fail t > t_min >= 0 anyway, so every lane divides.
    [[gnu::always_inline]] static std::uint32_t plane_distances(const PlaneBlock& block, const Ray<Real>& ray, Real* t,
                                                                Real* denominator) {
        DirectPack normal[3], along[3];
        for (int axis = 0; axis < 3; ++axis) {
            normal[axis] = DirectPack::load(block.normal[axis]);
            along[axis] = DirectPack::load(block.point[axis]) - DirectPack::broadcast(ray.origin[axis]);
        }
        const DirectPack d = (DirectPack::broadcast(ray.direction.x) * normal[0] +
                              DirectPack::broadcast(ray.direction.y) * normal[1]) +
                             DirectPack::broadcast(ray.direction.z) * normal[2];
        const DirectPack numerator = (along[0] * normal[0] + along[1] * normal[1]) + along[2] * normal[2];
        const DirectPack distance = numerator / d;
        d.store(denominator);
        distance.store(t);
        const std::uint32_t met = ((d != DirectPack::broadcast(Real(0))) & (DirectPack::broadcast(ray.t_min) < distance)).bits();
        return met & block.lanes;
    }

    // A mesh of the top level small enough for one leaf (a transformed floor or plate of a few
    // triangles): the ray is taken to its object space and the leaf tested there, as the
    // instance's own index would after the top level's box test. Rays that leave the leaf's box
    // by a face are culled in object space first, as that index's slab test rejects them;
    // only rays the world box alone would have stopped are tested too, and they miss.
    struct alignas(64) DirectMesh {
        std::uint32_t object = 0;
        typename Mesh::Leaf leaf;
    };
    // Around each direct sphere, lane by lane, a world-space sphere widened so that may_hit
    // never rejects a ray the object-space test hits: it culls as the index's box did. Lanes
    // past the last sphere are masked off.
    struct DirectBounds {
        alignas(64) Real center[3][direct_width] = {};
        alignas(64) Real radius_squared[direct_width] = {};
        std::uint32_t lanes = 0;

        void set(std::size_t lane, const Vec3<Real>& sphere_center, double radius) {
            for (int axis = 0; axis < 3; ++axis) center[axis][lane] = sphere_center[axis];
            radius_squared[lane] = Real(radius * radius);
            lanes |= std::uint32_t(1) << lane;
        }
    };

    void choose_direct_top_level(const scene::Scene& scene) {
        if (top_objects_.empty() || top_objects_.size() > direct_limit) return;
        const std::size_t first_sphere = scene.meshes.size() + scene.mesh_instances.size();
        std::vector<DirectSphere> chosen;
        std::vector<DirectMesh> meshes;
        DirectBounds bounds;
        for (const std::uint32_t object : top_objects_) {
            const Instance& instance = instances_[object];
            if (instance.moving) return;
            if (instance.kind == Kind::mesh) {
                const std::optional<typename Mesh::Leaf> leaf = meshes_[instance.shape].single_leaf();
                if (!leaf) return;
                meshes.push_back({object, *leaf});
                continue;
            }
            DirectSphere direct;
            direct.object = object;
            if (instance.transformed) {
                direct.map = Mat3<Real>(instance.world_to_object) == Mat3<Real>(1) ? DirectSphere::Map::translation
                                                                                   : DirectSphere::Map::matrix;
                direct.translation = Vec3<Real>(instance.world_to_object[3]);
            }
            // |M (c + r u) - M c| <= r ||M||_2, and ||M||_2 <= min(||M||_F, sqrt(||M||_1 ||M||_inf)):
            // 1 for a translation, the largest factor for a scaling. Widened by 0.1% for the
            // rounded matrices and the object-space test's rounding.
            const scene::Sphere& source = scene.spheres[object - first_sphere];
            const glm::dmat3 linear(source.transform);
            double frobenius = 0, columns = 0, rows = 0;
            for (int i = 0; i < 3; ++i) {
                frobenius += glm::dot(linear[i], linear[i]);
                columns = std::max(columns, std::abs(linear[i][0]) + std::abs(linear[i][1]) + std::abs(linear[i][2]));
                rows = std::max(rows, std::abs(linear[0][i]) + std::abs(linear[1][i]) + std::abs(linear[2][i]));
            }
            const double radius = source.radius * std::sqrt(std::min(frobenius, columns * rows)) * (1 + 1e-3);
            bounds.set(chosen.size(), Vec3<Real>(glm::dvec3(source.transform * glm::dvec4(source.center, 1.0))), radius);
            chosen.push_back(direct);
        }
        // The meshes' lanes follow the spheres': a world-space sphere around each one's world
        // box (conservative: add_instance rounds it outwards), so that rays passing far from a
        // small transformed mesh are culled before the object-space transform and leaf test.
        // Without it, hw2 simple_transform (two rotated meshes, a sphere) took 1.3x the CPU
        // time of the index, whose world boxes had culled those rays.
        for (std::size_t m = 0; m < meshes.size(); ++m) {
            const Aabb<Real>& box = instances_[meshes[m].object].world_bounds;
            const glm::dvec3 low(box.min), high(box.max);
            const glm::dvec3 exact_center = 0.5 * (low + high);
            const Vec3<Real> center(exact_center);
            // The half diagonal, plus how far rounding moved the centre, widened as above.
            const double radius =
                (0.5 * glm::length(high - low) + glm::length(glm::dvec3(center) - exact_center)) * (1 + 1e-3);
            bounds.set(chosen.size() + m, center, radius);
        }
        direct_spheres_ = std::move(chosen);
        direct_meshes_ = std::move(meshes);
        direct_bounds_ = bounds;
        direct_top_ = true;
    }

    // Which direct objects the ray may meet (bit i for sphere i, then the meshes' bits after
    // the spheres' as choose_direct_top_level lays them out): lane by lane, false only where
    // it surely misses, starting outside and leaving, or passing wider than the radius
    // (a |oc|^2 - b^2 > a r^2, no division). The rounded oc, b and products are off by at most
    // 8 epsilon a |oc|^2 in all (the cancellation when the ray aims at the centre); the test
    // allows twice that. Each lane computes what the scalar dot products compute, in their order.
    [[gnu::always_inline]] std::uint32_t may_hit(const Ray<Real>& ray) const {
        const DirectBounds& bounds = direct_bounds_;
        DirectPack oc[3];
        for (int axis = 0; axis < 3; ++axis)
            oc[axis] = DirectPack::broadcast(ray.origin[axis]) - DirectPack::load(bounds.center[axis]);
        const DirectPack dx = DirectPack::broadcast(ray.direction.x), dy = DirectPack::broadcast(ray.direction.y),
                         dz = DirectPack::broadcast(ray.direction.z);
        const DirectPack b = (oc[0] * dx + oc[1] * dy) + oc[2] * dz;
        const DirectPack distance_squared = (oc[0] * oc[0] + oc[1] * oc[1]) + oc[2] * oc[2];
        const DirectPack radius_squared = DirectPack::load(bounds.radius_squared);
        std::uint32_t leaving = 0;
        if (ray.t_min >= 0) leaving = ((DirectPack::broadcast(Real(0)) <= b) & (radius_squared < distance_squared)).bits();
        const DirectPack a = DirectPack::broadcast(glm::dot(ray.direction, ray.direction));
        const DirectPack slack = DirectPack::broadcast(16 * std::numeric_limits<Real>::epsilon());
        const std::uint32_t near = (a * distance_squared - b * b <= a * (radius_squared + slack * distance_squared)).bits();
        return near & ~leaving & bounds.lanes;
    }

    // Whether the ray meets `sphere` in (ray.t_min, t_max], tested in object space as the index's
    // leaf tests it (to_object); for the spheres may_hit lets through.
    [[gnu::always_inline]] bool direct_hit(const DirectSphere& sphere, const Ray<Real>& ray, Real t_max, Real& t) const {
        const Instance& instance = instances_[sphere.object];
        const SphereShape<Real>& shape = spheres_[instance.shape];
        switch (sphere.map) {
            case DirectSphere::Map::none: return shape.intersect(ray, ray.t_min, t_max, t);
            case DirectSphere::Map::translation: {
                Ray<Real> local = ray;
                local.origin = ray.origin + sphere.translation;
                return shape.intersect(local, ray.t_min, t_max, t);
            }
            case DirectSphere::Map::matrix: break;
        }
        return shape.intersect(instance.to_object(ray), ray.t_min, t_max, t);
    }

    // The direct objects may_hit lets through, as bits of direct_spheres_ and of direct_meshes_.
    struct DirectLanes {
        std::uint32_t spheres = 0, meshes = 0;
    };
    [[gnu::always_inline]] DirectLanes direct_lanes(const Ray<Real>& ray) const {
        if (direct_bounds_.lanes == 0) return {};
        const std::uint32_t may = may_hit(ray);
        const std::size_t spheres = direct_spheres_.size();
        return {may & ((std::uint32_t(1) << spheres) - 1), may >> spheres};
    }
    // A direct mesh's ray in its object space, or none where its leaf's box culls it there.
    [[gnu::always_inline]] std::optional<Ray<Real>> direct_mesh_ray(const DirectMesh& direct, const Ray<Real>& ray) const {
        const Ray<Real> local = to_object(instances_[direct.object], ray);
        if (leaves_box(direct.leaf.box, local)) return std::nullopt;
        return local;
    }

    // intersect's top level and planes for direct_spheres_; `found`: a world mesh was hit.
    template <BackfaceCulling Culling>
    bool intersect_direct(Ray<Real>& ray, Hit<Real>& hit, bool found) const {
        const DirectLanes may = direct_lanes(ray);
        for (std::uint32_t lanes = may.spheres; lanes != 0; lanes &= lanes - 1) {
            const DirectSphere& sphere = direct_spheres_[std::size_t(std::countr_zero(lanes))];
            Real t;
            if (!direct_hit(sphere, ray, ray.t_max, t)) continue;
            ray.t_max = t;
            hit.t = t;
            hit.primitive = 0;
            hit.b1 = hit.b2 = 0;  // a sphere's whole record, as intersect_instance writes it
            hit.object = sphere.object;
            found = true;
        }
        return intersect_direct_meshes<Culling>(ray, hit, may.meshes, found);
    }

    // The spheres of the direct top level against up to direct_width rays, one in each lane
    // (intersect_each): sphere after sphere in intersect_direct's order, each lane's may_hit
    // lane and SphereShape::intersect computed with their operations in their order, so each
    // lane finds what intersect_direct's sphere loop finds for its ray (its t_max lowered, its
    // hit's t, primitive and object set, its bit of `found` set). Spheres mapped by a matrix
    // (ellipsoids) are tested ray by ray. AnyHit: occluded_direct's question instead, a hit
    // below t_max (open) setting the lane's bit of `found`, and nothing else written.
    template <bool AnyHit = false>
    void intersect_direct_spheres_lanes(std::conditional_t<AnyHit, const Ray<Real>*, Ray<Real>*> rays, Hit<Real>* hits,
                                        int count, std::uint32_t& found) const {
        alignas(64) Real fields[8][direct_width];
        for (int lane = 0; lane < direct_width; ++lane) {
            const Ray<Real>& ray = rays[lane < count ? lane : 0];
            for (int axis = 0; axis < 3; ++axis) {
                fields[axis][lane] = ray.origin[axis];
                fields[3 + axis][lane] = ray.direction[axis];
            }
            fields[6][lane] = ray.t_min;
            fields[7][lane] = ray.t_max;
        }
        const DirectPack o[3] = {DirectPack::load(fields[0]), DirectPack::load(fields[1]), DirectPack::load(fields[2])};
        const DirectPack d[3] = {DirectPack::load(fields[3]), DirectPack::load(fields[4]), DirectPack::load(fields[5])};
        const DirectPack t_min = DirectPack::load(fields[6]);
        DirectPack t_max = DirectPack::load(fields[7]);
        const DirectPack zero = DirectPack::broadcast(0);
        const auto dot = [](const DirectPack* x, const DirectPack* y) { return (x[0] * y[0] + x[1] * y[1]) + x[2] * y[2]; };
        const DirectPack a = dot(d, d);  // glm::dot(direction, direction), as may_hit and the sphere test take it
        const std::uint32_t rays_present = (std::uint32_t(1) << count) - 1;
        const std::uint32_t starts_ahead = (t_min >= zero).bits();
        const DirectPack slack = DirectPack::broadcast(16 * std::numeric_limits<Real>::epsilon());
        for (std::size_t s = 0; s < direct_spheres_.size(); ++s) {
            // may_hit's lane s, for every ray.
            DirectPack to_bound[3];
            for (int axis = 0; axis < 3; ++axis)
                to_bound[axis] = o[axis] - DirectPack::broadcast(direct_bounds_.center[axis][s]);
            const DirectPack along = dot(to_bound, d), distance_squared = dot(to_bound, to_bound);
            const DirectPack radius_squared = DirectPack::broadcast(direct_bounds_.radius_squared[s]);
            const std::uint32_t leaving = ((zero <= along) & (radius_squared < distance_squared)).bits() & starts_ahead;
            const std::uint32_t near =
                (a * distance_squared - along * along <= a * (radius_squared + slack * distance_squared)).bits();
            std::uint32_t may = near & ~leaving & rays_present;
            if constexpr (AnyHit) may &= ~found;
            if (may == 0) continue;

            const DirectSphere& sphere = direct_spheres_[s];
            if (sphere.map == DirectSphere::Map::matrix) {
                for (; may != 0; may &= may - 1) {
                    const int i = std::countr_zero(may);
                    Real t;
                    if (!direct_hit(sphere, rays[i], rays[i].t_max, t)) continue;
                    if constexpr (AnyHit) {
                        if (t < rays[i].t_max) found |= std::uint32_t(1) << i;
                        continue;
                    } else {
                        rays[i].t_max = t;
                        hits[i].t = t;
                        hits[i].primitive = 0;
                        hits[i].b1 = hits[i].b2 = 0;
                        hits[i].object = sphere.object;
                        found |= std::uint32_t(1) << i;
                    }
                }
                if constexpr (!AnyHit) {
                    for (int i = 0; i < count; ++i) fields[7][i] = rays[i].t_max;
                    t_max = DirectPack::load(fields[7]);
                }
                continue;
            }
            // SphereShape::intersect, from the origin direct_hit gives it.
            const SphereShape<Real>& shape = spheres_[instances_[sphere.object].shape];
            DirectPack oc[3];
            for (int axis = 0; axis < 3; ++axis) {
                const DirectPack origin = sphere.map == DirectSphere::Map::translation
                                              ? o[axis] + DirectPack::broadcast(sphere.translation[axis])
                                              : o[axis];
                oc[axis] = origin - DirectPack::broadcast(shape.center[axis]);
            }
            const DirectPack r2 = DirectPack::broadcast(shape.radius * shape.radius);
            const DirectPack half_b = dot(oc, d);
            const DirectPack c = dot(oc, oc) - r2;
            may &= ~(((half_b >= zero) & (c > zero)).bits() & starts_ahead);
            const DirectPack scale = half_b / a;
            DirectPack perpendicular[3];
            for (int axis = 0; axis < 3; ++axis) perpendicular[axis] = oc[axis] - scale * d[axis];
            const DirectPack discriminant_over_a = r2 - dot(perpendicular, perpendicular);
            may &= ~(discriminant_over_a < zero).bits();
            if (may == 0) continue;
            const DirectPack root = sqrt(a * discriminant_over_a);
            const DirectPack q = select(half_b >= zero, -(half_b + root), -(half_b - root));
            const auto q_zero = q == zero;
            const DirectPack t0 = select(q_zero, zero, c / q), t1 = select(q_zero, zero, q / a);
            const auto swap = t0 > t1;
            const DirectPack nearer = select(swap, t1, t0), farther = select(swap, t0, t1);
            const auto nearer_in = (nearer > t_min) & (nearer <= t_max);
            const auto farther_in = (farther > t_min) & (farther <= t_max);
            const DirectPack t = select(nearer_in, nearer, farther);
            if constexpr (AnyHit) {
                found |= ((nearer_in | farther_in) & (t < t_max)).bits() & may;
            } else {
                std::uint32_t taken = (nearer_in | farther_in).bits() & may;
                if (taken == 0) continue;
                alignas(64) Real t_lanes[direct_width];
                t.store(t_lanes);
                for (; taken != 0; taken &= taken - 1) {
                    const int i = std::countr_zero(taken);
                    rays[i].t_max = fields[7][i] = t_lanes[i];
                    hits[i].t = t_lanes[i];
                    hits[i].primitive = 0;
                    hits[i].b1 = hits[i].b2 = 0;
                    hits[i].object = sphere.object;
                    found |= std::uint32_t(1) << i;
                }
                t_max = DirectPack::load(fields[7]);
            }
        }
    }

    // The lanes of rays[0, n), less those of `skip`, whose ray may reach `leaf`: intersect's
    // and occluded's own leaves_box test, ray by ray.
    [[gnu::always_inline]] static std::uint32_t lanes_reaching(const typename Mesh::Leaf& leaf, const Ray<Real>* rays, int n,
                                                               std::uint32_t skip) {
        std::uint32_t lanes = 0;
        for (int i = 0; i < n; ++i)
            if (!((skip >> i) & 1) && !leaves_box(leaf.box, rays[i])) lanes |= std::uint32_t(1) << i;
        return lanes;
    }
    // The rays' t_max, a lane each (the lanes past n copy ray 0's, as RayLanes does).
    template <class Packets>
    [[gnu::always_inline]] static typename Packets::LanePack lanes_t_max(const Ray<Real>* rays, int n) {
        alignas(64) Real limits[Packets::ray_lanes];
        for (int i = 0; i < Packets::ray_lanes; ++i) limits[i] = rays[i < n ? i : 0].t_max;
        return Packets::LanePack::load(limits);
    }

    // intersect_direct past its spheres: the direct meshes of `mesh_lanes` (direct_lanes), then
    // the planes; `found`: something nearer was hit.
    template <BackfaceCulling Culling>
    [[gnu::always_inline]] bool intersect_direct_meshes(Ray<Real>& ray, Hit<Real>& hit, std::uint32_t mesh_lanes, bool found) const {
        if constexpr (Mesh::packed) {
            for (std::uint32_t lanes = mesh_lanes; lanes != 0; lanes &= lanes - 1) {
                const DirectMesh& direct = direct_meshes_[std::size_t(std::countr_zero(lanes))];
                const std::optional<Ray<Real>> local = direct_mesh_ray(direct, ray);
                if (!local) continue;
                const Mesh& mesh = meshes_[instances_[direct.object].shape];
                const TriangleRay triangle_ray(*local);
                const bool cull = culls_back_faces(Culling);
                if (cull ? mesh.template intersect_leaf<true>(*local, triangle_ray, direct.leaf, ray.t_max, hit)
                         : mesh.template intersect_leaf<false>(*local, triangle_ray, direct.leaf, ray.t_max, hit)) {
                    hit.object = direct.object;
                    found = true;
                }
            }
        }
        return intersect_planes<Culling>(ray, hit) || found;
    }

    bool occluded_direct(const Ray<Real>& ray) const {
        const DirectLanes may = direct_lanes(ray);
        for (std::uint32_t lanes = may.spheres; lanes != 0; lanes &= lanes - 1) {
            const DirectSphere& sphere = direct_spheres_[std::size_t(std::countr_zero(lanes))];
            Real t;
            if (direct_hit(sphere, ray, ray.t_max, t) && t < ray.t_max) return true;
        }
        if constexpr (Mesh::packed) {
            for (std::uint32_t lanes = may.meshes; lanes != 0; lanes &= lanes - 1) {
                const DirectMesh& direct = direct_meshes_[std::size_t(std::countr_zero(lanes))];
                const std::optional<Ray<Real>> local = direct_mesh_ray(direct, ray);
                if (local && meshes_[instances_[direct.object].shape].occluded_leaf(*local, TriangleRay(*local), direct.leaf, ray.t_max))
                    return true;
            }
        }
        return occluded_by_planes(ray);
    }

    // A scene whose top level is tested without its index (direct spheres, or nothing but the
    // world-space meshes and planes) and whose world-space indices are each one leaf (at most N
    // triangles: the course's floors, walls and mirrors of two to six) is tested without the
    // TraversalRay: each index's leaf directly (TriangleMesh::intersect_leaf), then the spheres
    // and planes. The TraversalRay (three divisions, broadcast) and the root's box test were
    // a fifth of hw1 simple_reflectance's profile (a two-triangle floor and one sphere). An
    // index whose root holds two leaves is tested leaf by leaf too (intersect_root_leaves:
    // hw1 ocornellbox's ten wall triangles, where the TraversalRay, the root's test made twice
    // and the traversal were 15% of the profile). The
    // hits are the index's: traversal of a single leaf tests that leaf, in the same slot order
    // with the same t_max; only a ray whose box test the index would fail is now tested too,
    // and the conservative box (Ize's widened exit) fails only rays that miss the triangles.
    // A scene with a top-level index keeps it, and its TraversalRay, but its world-space
    // indices of one or two leaves are still tested leaf by leaf (intersect_indexed): hw2
    // horse_instanced's two-triangle floor had cost each camera ray a root test and a
    // traversal of their own, 7% of its instructions.
    void choose_direct_world_meshes() {
        for (WorldMeshes& group : world_meshes_) group.leaves = index_of(group).root_leaves();
        if (!top_objects_.empty() && !direct_top_) return;
        bool two_leaves = false;
        for (const WorldMeshes& group : world_meshes_) {
            if (!group.leaves) return;
            two_leaves |= group.leaves->count == 2;
        }
        direct_ = true;
        two_leaves_ = two_leaves;
    }

    // Whether the ray starts outside the box beyond one of its faces and does not move towards
    // it (a floor's rays that start above it and go up: most shadow and reflected rays), with
    // t_min >= 0. The index's slab test rejects every such ray without a division: the far
    // plane's distance (face - origin) / direction is negative, or -inf for a zero direction
    // of either sign, or the near plane's +inf, so the exit falls below the entry. (Only a
    // distance that underflows to -0, an origin within a subnormal's width of the face, would
    // pass that test; the ray then starts on the box and the leaf test decides, as here.)
    [[gnu::always_inline]] static bool leaves_box(const Aabb<Real>& box, const Ray<Real>& ray) {
        bool away = false;
        for (int axis = 0; axis < 3; ++axis)
            away |= (ray.origin[axis] > box.max[axis] && ray.direction[axis] >= 0) |
                    (ray.origin[axis] < box.min[axis] && ray.direction[axis] <= 0);
        return away && ray.t_min >= 0;
    }

    // The world-space meshes' leaves for intersect's direct path: hit or not, and hit filled as
    // intersect's loop over the indices fills it.
    // TwoLeaves: some index has two (two_leaves_); without it, the one-leaf code alone.
    template <BackfaceCulling Culling, bool TwoLeaves>
    bool intersect_world_leaves(Ray<Real>& ray, Hit<Real>& hit) const {
        if constexpr (Mesh::packed) {
            std::optional<TriangleRay> triangle_ray;  // made for the first leaf the ray may reach
            bool found = false;
            for (const WorldMeshes& group : world_meshes_) {
                const Mesh& index = index_of(group);
                const bool cull = culls_back_faces(Culling);
                const bool group_hit = cull ? intersect_root_leaves<true, TwoLeaves>(index, *group.leaves, ray, triangle_ray, hit)
                                            : intersect_root_leaves<false, TwoLeaves>(index, *group.leaves, ray, triangle_ray, hit);
                if (group_hit) {
                    if (group.index) group.attribute(index.source_triangle(hit.primitive), hit);
                    else hit.object = group.objects[0];
                    found = true;
                }
            }
            return found;
        } else {
            return false;  // root_leaves() is empty without packets: direct_ stays false
        }
    }

    // One index's closest hit from its root's one or two leaves, the hit its traversal finds.
    // Two leaves are each tested up to the ray's own t_max, without their boxes' order: a leaf's
    // test keeps its closest candidate at or below t_max (later slots winning ties), so under
    // the lower t_max the nearer leaf's hit leaves the farther one, it is the same candidate
    // where it passes, and the strictly nearer of the two hits is what either order of visits
    // ends with. Only equal distances depend on the order (the later leaf wins), and the
    // traversal orders leaves by their boxes' entry distances: those rays (an edge shared by
    // the two leaves) are handed to the traversal itself, from the state before either leaf.
    template <bool CullBackfaces, bool TwoLeaves>
    [[gnu::always_inline]] static bool intersect_root_leaves(const Mesh& index, const typename Mesh::RootLeaves& leaves,
                                                             Ray<Real>& ray, std::optional<TriangleRay>& triangle_ray,
                                                             Hit<Real>& hit) {
        const auto& first = leaves.leaf[0];
        if (!TwoLeaves || leaves.count == 1) {
            if (leaves_box(first.box, ray)) return false;
            if (!triangle_ray) triangle_ray.emplace(ray);
            return index.template intersect_leaf<CullBackfaces>(ray, *triangle_ray, first, ray.t_max, hit);
        }
        const auto& second = leaves.leaf[1];
        const bool may_first = !leaves_box(first.box, ray), may_second = !leaves_box(second.box, ray);
        if (!may_first && !may_second) return false;
        if (!triangle_ray) triangle_ray.emplace(ray);
        Real t_first = ray.t_max, t_second = ray.t_max;
        Hit<Real> hit_first = hit, hit_second = hit;
        const bool found_first =
            may_first && index.template intersect_leaf<CullBackfaces>(ray, *triangle_ray, first, t_first, hit_first);
        const bool found_second =
            may_second && index.template intersect_leaf<CullBackfaces>(ray, *triangle_ray, second, t_second, hit_second);
        if (found_first && found_second && t_first == t_second)
            return index.template intersect<CullBackfaces>(ray, TraversalRay(ray), *triangle_ray, ray.t_max, hit);
        if (found_second && (!found_first || t_second < t_first)) {
            ray.t_max = t_second;
            hit = hit_second;
            return true;
        }
        if (!found_first) return false;
        ray.t_max = t_first;
        hit = hit_first;
        return true;
    }

    // occluded for direct_: the world meshes' leaves, then the direct top level and planes.
    [[gnu::always_inline]] bool occluded_without_index(const Ray<Real>& ray) const {
        return (!world_meshes_.empty() && (two_leaves_ ? occluded_world_leaves<true>(ray) : occluded_world_leaves<false>(ray))) ||
               occluded_direct(ray);
    }

    template <bool TwoLeaves>
    bool occluded_world_leaves(const Ray<Real>& ray) const {
        if constexpr (Mesh::packed) {
            std::optional<TriangleRay> triangle_ray;
            for (const WorldMeshes& group : world_meshes_) {
                const Mesh& index = index_of(group);
                for (int i = 0; i < (TwoLeaves ? group.leaves->count : 1); ++i) {
                    const auto& leaf = group.leaves->leaf[std::size_t(i)];
                    if (leaves_box(leaf.box, ray)) continue;
                    if (!triangle_ray) triangle_ray.emplace(ray);
                    if (index.occluded_leaf(ray, *triangle_ray, leaf, ray.t_max)) return true;
                }
            }
        }
        return false;
    }

    // The merged meshes and the index over their triangles.
    struct WorldMeshes {
        // Over the parts' triangles, numbered part after part; none for a single part, which
        // is traversed through its own mesh's index (and keeps its index order).
        std::optional<Mesh> index;
        std::vector<std::uint32_t> objects;         // per part, its object (Hit::object)
        std::vector<std::uint32_t> first_triangle;  // per part, the number of its first triangle
        std::optional<typename Mesh::RootLeaves> leaves;  // the index's leaves, when its root has only one or two (direct_)

        // The hit on triangle `number` of the index (hit.primitive holds the index's slot)
        // as a hit on its own mesh: its object, its triangle there (the file's order, which
        // its ShadingOnly mesh keeps).
        void attribute(std::uint32_t number, Hit<Real>& hit) const {
            const std::size_t part =
                std::size_t(std::upper_bound(first_triangle.begin(), first_triangle.end(), number) - first_triangle.begin()) - 1;
            hit.object = objects[part];
            hit.primitive = number - first_triangle[part];
        }
    };
    // The index a world group is traversed through: its merged index, or its one part's own.
    const Mesh& index_of(const WorldMeshes& group) const { return group.index ? *group.index : meshes_[group.objects[0]]; }

    std::vector<TriangleMesh<Real, Policy>> meshes_;
    std::vector<WorldMeshes> world_meshes_;
    std::vector<std::uint32_t> top_objects_;  // the top level's primitives: the objects not merged
    // The top level's objects when it is tested without its index (direct_top_).
    std::vector<DirectSphere> direct_spheres_;
    std::vector<DirectMesh> direct_meshes_;
    bool direct_top_ = false;
    DirectBounds direct_bounds_;
    bool direct_ = false;  // no TraversalRay: the top level direct, the world meshes' leaves too
    bool two_leaves_ = false;  // some world-space index of direct_ has a root of two leaves
    Aabb<Real> bounds_;
    std::vector<SphereShape<Real>> spheres_;
    std::vector<PlaneShape<Real>> planes_;
    std::vector<PlaneBlock> plane_blocks_;  // planes_, eight to a block
    std::vector<std::uint32_t> plane_materials_;
    std::vector<std::uint32_t> plane_textures_;
    // Each object's texture indices; entry 0 is the empty list that untextured objects share.
    std::vector<std::vector<std::uint32_t>> texture_lists_{1};
    std::vector<Instance> instances_;
    std::vector<Vec3<Real>> emitted_;  // per instance, in instances_'s order
    std::vector<InstanceTransforms<Real>> transforms_;
    Index top_;
};

// The geometry a renderer builds for an acceleration policy: a SceneGeometry traversed by the
// policy's own indices, unless the policy brings its own Geometry (Embree, accel/embree.hpp).
template <class Policy, Scalar Real, bool MotionBlur>
struct GeometryOf {
    using type = SceneGeometry<Real, Policy, MotionBlur>;
};
template <class Policy, Scalar Real, bool MotionBlur>
    requires requires { typename Policy::template Geometry<Real, MotionBlur>; }
struct GeometryOf<Policy, Real, MotionBlur> {
    using type = typename Policy::template Geometry<Real, MotionBlur>;
};

}  // namespace prism
