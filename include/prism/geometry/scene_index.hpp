// What finds the hits of a scene, in the renderer's precision: the meshes' own indices (built
// once per mesh; a MeshInstance costs one placement, never a copy of its mesh or its index),
// spheres and planes, under a top-level index over the objects. This is the two-level
// hierarchy. The meshes already in world space (no transformation, not moving, not instanced)
// share one index over all their triangles instead, traversed beside the top level. A top level
// of a few objects is tested without its index (geometry/direct_top_level.hpp).
// The query seam's two entries (geometry/ray_batch.hpp) are its only way in: intersect for
// closest hits, occluded for any hits, each over a batch of rays. Batches side by side are
// geometry/scene_index_lanes.hpp. What a hit means is SceneSurfaces'; SceneGeometry pairs the two.
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/accel/accelerator.hpp>
#include <prism/geometry/backface_culling.hpp>
#include <prism/geometry/direct_top_level.hpp>
#include <prism/geometry/hit.hpp>
#include <prism/geometry/placement.hpp>
#include <prism/geometry/planes.hpp>
#include <prism/geometry/ray_batch.hpp>
#include <prism/geometry/sphere.hpp>
#include <prism/geometry/triangle_mesh.hpp>
#include <prism/memory/unconstructed.hpp>
#include <prism/scene/needs.hpp>
#include <prism/scene/scene.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <optional>
#include <span>
#include <type_traits>
#include <vector>

namespace prism {

template <Scalar Real, class Policy, bool MotionBlur = false>
    requires AccelerationPolicy<Policy, Real>
class SceneIndex {
public:
    using Index = typename Policy::template Index<Real>;
    using Mesh = TriangleMesh<Real, Policy>;

    explicit SceneIndex(const scene::Scene& scene)
        : planes_(scene, std::uint32_t(scene.meshes.size() + scene.mesh_instances.size() + scene.spheres.size())) {
        const std::vector<bool> merged = merged_meshes(scene);
        // A single merged mesh needs no merged index: it keeps its own, read without the
        // translation a merged index's hits need (a cache miss per hit ray on the 766k-triangle
        // dragon: 5-9% of its camera rays' time).
        const bool alone = std::count(merged.begin(), merged.end(), true) == 1;
        const std::uint32_t world_leaf_size = world_max_leaf_size(scene, merged);
        meshes_.reserve(scene.meshes.size());
        for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
            if (merged[m] && !alone) meshes_.emplace_back(std::nullopt);
            else meshes_.emplace_back(std::in_place, scene.meshes[m], merged[m] ? world_leaf_size : 0);
        }
        placements_ = place_objects<Real>(
            scene, [&](std::size_t m) { return meshes_[m] ? meshes_[m]->bounds() : Mesh::bounds_of(scene.meshes[m]); },
            MotionBlur);
        for (const auto& sphere : scene.spheres) spheres_.push_back({Vec3<Real>(sphere.center), Real(sphere.radius)});
        // One index over the merged meshes, flat and smooth alike (they are culled alike), the
        // object of mesh m being object m.
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
            if (parts.size() > 1) group.index.emplace(std::span<const scene::Mesh* const>(parts), world_leaf_size);
            if (!parts.empty()) world_meshes_.push_back(std::move(group));
        }
        std::vector<Aabb<Real>> boxes;
        for (std::uint32_t object = 0; object < placements_.size(); ++object) {
            bounds_.extend(placements_[object].world_bounds);
            if (object < merged.size() && merged[object]) continue;
            top_objects_.push_back(object);
            boxes.push_back(placements_[object].world_bounds);
        }
        // One object per leaf where the index takes the option: testing an object (a
        // transform, then its mesh's own BVH or its sphere) costs far more than the box test
        // that could skip it. With the wide BVH's leaves of up to 8, a scene of a few objects
        // was one leaf, and every ray entered every object (hw2 ellipsoids, the course's
        // Cornell boxes: 1.0-1.3x the time of the binary BVH before the wide one).
        BvhBuildOptions top_options;
        top_options.max_leaf_size = 1;
        if constexpr (requires { Index::build(boxes, top_options); }) top_ = Index::build(boxes, top_options);
        else top_ = Index::build(boxes);
        direct_.choose(scene, top_objects_, placements_, spheres_, meshes_);
        choose_direct_world_meshes();
    }

    // The leaves of the world-space index (0: its builder's choice). A scene with a path-traced
    // camera whose world-space meshes are a room (at most 64 triangles: walls, a ceiling, a light
    // box) gets leaves of at most two triangles, a rectangle each. The surface area heuristic
    // weighs a box by the chance that a ray from outside meets it, and so puts a room's walls
    // into one leaf whose box is the room; a path tracer's rays start on the walls (bounces, and
    // next-event shadow rays), so every one of them tested that leaf's packet. With a wall to a
    // leaf, a shadow ray from the floor to the light enters none of the walls' flat boxes. hw7
    // path_diffuse and path_glass took 0.89 and 0.94 of the time, the same images (one triangle
    // a leaf: 0.98 and 1.06; bench/RESULTS.md, "Path tracer"). Fabianowski, Fowler and
    // Dingliana's cost for rays that start inside the scene (Eurographics 2009 short papers) is
    // the general form. Not for the ray tracer's scenes: its rays are mostly camera rays, the
    // hw1 Cornell boxes took 0.95-1.03 of the time that way, and three of their images changed
    // where a ray meets two walls at the same distance (the leaves' order decides such ties).
    static std::uint32_t world_max_leaf_size(const scene::Scene& scene) { return world_max_leaf_size(scene, merged_meshes(scene)); }

    // The objects as this index placed them (place_objects), for the surfaces that pair with it.
    std::span<const Placement<Real>> placements() const { return placements_; }
    // The order in which hits name mesh m's triangles (Hit::primitive): its own index's slots,
    // or the file's (empty) for a mesh merged into a world-space index, whose hits are
    // attributed to their meshes in the file's numbering.
    std::span<const std::uint32_t> slot_order(std::size_t m) const {
        if (meshes_[m]) return meshes_[m]->slot_order();
        return {};
    }
    Aabb<Real> bounds() const { return bounds_; }
    // The indices of both levels, the merged world-space index, and the triangles their leaves
    // test (bench/scaling_bench.cpp).
    std::size_t accelerator_bytes() const {
        std::size_t total = top_.memory_bytes();
        for (const auto& mesh : meshes_)
            if (mesh) total += mesh->accelerator_bytes();
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

    // The one closest-hit entry (geometry/ray_batch.hpp): for each active ray, the closest hit in
    // (t_min, t_max], its t_max lowered to it and hits[i] filled; bit i set where rays[i] hits.
    // The batch's culling rule names the surfaces skipped when met from behind
    // (geometry/backface_culling.hpp). Every ray's hit is the one it gets alone, to the bit,
    // however the batch is traversed (closest_many decides): a hit depends on the order in
    // which leaves are visited only when two candidates tie, and a ray whose hit in a lane
    // traversal came at exactly the t_max it was given is traced again on its own.
    // A batch of one is inlined into the caller down to closest_one's dispatch.
    // Every route below tests every surface but the planes; the entry tests the planes last,
    // from the t_max the route leaves (where each route had tested them, so the same hits).
    // Only BackfaceCulling::all culls planes, and triangles cull under both rules that cull
    // (culls_planes, culls_back_faces). Both are run-time choices: the routes take the
    // triangles' as `cull`, which the leaf tests read only where a triangle is hit, and the
    // planes take theirs here. Compiled for each rule, every route was two or three copies:
    // each copy an eighth of the prism binary's code.
    PRISM_FORCE_INLINE std::uint32_t intersect(const RayBatch<Real>& batch, Hit<Real>* hits) const {
        if (batch.count == 1) {
            if (!(batch.active & 1)) return 0;
            Ray<Real>& ray = batch.rays[0];
            const bool found = closest_one(ray, hits[0], culls_back_faces(batch.culling));
            return planes_.closest(ray, hits[0], culls_planes(batch.culling)) || found;
        }
        return closest_many(batch, hits);
    }

    // The one any-hit entry: bit i set where something lies in (t_min, t_max) of active ray i
    // (open at t_max: a shadow ray aimed at a point on a surface is not blocked by it).
    PRISM_FORCE_INLINE std::uint32_t occluded(const RayBatch<Real>& batch) const {
        if (batch.count == 1) return (batch.active & 1) && occluded_one(batch.rays[0]);
        return occluded_many(batch);
    }

    // The one rule for how a batch of several rays is traversed, closest and any hits alike:
    // with triangle packets, a scene whose direct form tests its leaves and spheres with a ray
    // in each lane (intersection_batches) takes them so; a scene with an index (no direct form)
    // takes up to index_lanes rays through it together (the nodes' tests of several rays then
    // overlap instead of each waiting on the one before); elsewhere (top-level meshes tested
    // directly, no packets) the rays go one by one. So do batches of
    // fewer than side_by_side_rays active rays, as Embree's hybrid traversal drops to single
    // rays when few stay active: a point's shadow rays to its two lights cost hw2
    // horse_and_glass_mug 1.11 times its time through the index together (lane set-up and
    // masks for two rays going different ways), and the ray tracer had sent them one by one.
    static constexpr int side_by_side_rays = 4;
    BatchRoute route(int active_rays = RayBatch<Real>::max_rays) const {
        if (active_rays < side_by_side_rays) return BatchRoute::ray_by_ray;
        if constexpr (Mesh::packed) {
            if (intersection_batches()) return BatchRoute::leaf_lanes;
            if (!direct_form_) return BatchRoute::index_lanes;
        }
        return BatchRoute::ray_by_ray;
    }


private:
    // One ray's closest hit among every surface but the planes. The small scenes' direct form
    // is a dispatch to two out-of-line functions, and is inlined into the caller; the indexed
    // form stays one out-of-line function. GCC weighed the two as one: once the kernel's slab
    // test changed size it stopped inlining the whole, and every camera ray of the sphere
    // scenes paid a call and its spills (3% of hw1 simple_shading's CPU time, 8-13% of hw1
    // two_spheres').
    PRISM_FORCE_INLINE bool closest_one(Ray<Real>& ray, Hit<Real>& hit, bool cull) const {
        if (direct_form_) {
            const bool found = !world_meshes_.empty() && (several_leaves_ ? intersect_world_leaves<true>(ray, hit, cull)
                                                                       : intersect_world_leaves<false>(ray, hit, cull));
            return direct_.closest(ray, hit, found, cull);
        }
        return intersect_indexed(ray, hit, cull);
    }

    // A batch of several rays, traversed as route() says: side by side, the active rays first
    // gathered to the front if the mask has gaps (closest_dense), or ray by ray.
    std::uint32_t closest_many(const RayBatch<Real>& batch, Hit<Real>* hits) const {
        std::uint32_t found = closest_gathered(batch, hits, culls_back_faces(batch.culling));
        if (planes_.empty()) return found;
        const bool cull_planes = culls_planes(batch.culling);
        for (std::uint32_t lanes = batch.active; lanes != 0; lanes &= lanes - 1) {
            const int i = std::countr_zero(lanes);
            if (planes_.closest(batch.rays[i], hits[i], cull_planes)) found |= std::uint32_t(1) << i;
        }
        return found;
    }
    std::uint32_t closest_gathered(const RayBatch<Real>& batch, Hit<Real>* hits, bool cull) const {
        const BatchRoute way = route(std::popcount(batch.active));
        if (way == BatchRoute::ray_by_ray) {
            std::uint32_t found = 0;
            for (std::uint32_t lanes = batch.active; lanes != 0; lanes &= lanes - 1) {
                const int i = std::countr_zero(lanes);
                if (closest_one(batch.rays[i], hits[i], cull)) found |= std::uint32_t(1) << i;
            }
            return found;
        }
        if (batch.dense()) return closest_dense(way, batch.rays, hits, batch.count, cull);
        Gathered gathered(batch);
        Hit<Real> gathered_hits[RayBatch<Real>::max_rays];
        for (int k = 0; k < gathered.count; ++k) gathered_hits[k] = hits[gathered.index[k]];
        const std::uint32_t found = closest_dense(way, gathered.rays, gathered_hits, gathered.count, cull);
        for (int k = 0; k < gathered.count; ++k) {
            batch.rays[gathered.index[k]].t_max = gathered.rays[k].t_max;
            hits[gathered.index[k]] = gathered_hits[k];
        }
        return gathered.scatter(found);
    }

    // The any-hit query of one ray.
    PRISM_FORCE_INLINE bool occluded_one(const Ray<Real>& ray) const {
        if (direct_form_) return occluded_without_index(ray);
        return occluded_indexed(ray);
    }
    // Several rays, as route() says: side by side, or ray by ray over the active mask.
    std::uint32_t occluded_many(const RayBatch<Real>& batch) const {
        const BatchRoute way = route(std::popcount(batch.active));
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

    // intersect through the top-level index (scenes that chose no direct form).
    bool intersect_indexed(Ray<Real>& ray, Hit<Real>& hit, bool cull) const {
        const TraversalRay traversal_ray(ray);
        std::optional<TriangleRay> world_triangle_ray;  // made when the ray first enters a mesh
        // The merged world-space meshes first: their hit lowers t_max before the top level
        // tests any box. An index is entered without enters()'s pre-test, which repeats the
        // root's node test that traversal then makes (the same test, so the same hits): the
        // triangle set-up is made for nothing only for a ray that misses the root, and the
        // course's closest hits rarely do (the course mesh's primary rays: 0.92 of the time
        // with it, bench/RESULTS.md). Shadow rays keep it (occluded_indexed): many leave the
        // scene without a mesh.
        bool found = false;
        for (const WorldMeshes& group : world_meshes_) {
            const Mesh& index = index_of(group);
            bool group_hit = false;
            if (group.leaves) {
                if constexpr (Mesh::packed) {
                    group_hit = intersect_root_leaves<true>(index, *group.leaves, ray, world_triangle_ray, hit, cull);
                }
            } else {
                if (!world_triangle_ray) world_triangle_ray.emplace(ray);
                group_hit = index.intersect(ray, traversal_ray, *world_triangle_ray, ray.t_max, hit, cull);
            }
            if (group_hit) {
                if (group.index) group.attribute(index.source_triangle(hit.primitive), hit);
                else hit.object = group.objects[0];
                found = true;
            }
        }
        return intersect_top(ray, hit, found, traversal_ray, world_triangle_ray, cull);
    }

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
        if (direct_.chosen()) return occluded_direct(ray);
        const auto& order = top_.primitive_indices();
        const bool blocked =
            !top_objects_.empty() &&
            top_.traverse_any(traversal_ray, ray.t_min, ray.t_max, [&](std::uint32_t first, std::uint32_t count, Real& t_max) {
                for (std::uint32_t i = first; i < first + count; ++i)
                    if (occludes(placements_[top_objects_[order[i]]], ray, traversal_ray, world_triangle_ray, t_max))
                        return true;
                return false;
            });
        return blocked || planes_.occludes(ray);
    }

    // Whether closest_dense tests its rays side by side: scenes without an index (direct_form_),
    // under the packed watertight test, whose top level holds no mesh. The camera rays of hw1's
    // small scenes (a floor of two triangles under spheres, spheres alone) are such rays, and
    // so are the Cornell boxes' (a root of two to four leaves, tested leaf after leaf, a ray
    // whose hits in two leaves tie traced again alone: intersect_root_leaves' rule); batches
    // of their rays take 0.87-0.89 of the one-by-one time on hw1 cornellbox and ocornellbox
    // (bench/RESULTS.md, "Whole renders"). A top-level mesh (a transformed plate)
    // needs each ray's may_hit for its lane, which the spheres' lanes would only repeat (hw2
    // simple_transform, two rotated meshes and a sphere: 1.04 of the CPU time with them).
    bool intersection_batches() const {
        if constexpr (Mesh::packed) {
            if constexpr (Mesh::Packets::tests_ray_lanes) return direct_form_ && !direct_.has_meshes();
        }
        return false;
    }

    // Batches side by side (geometry/scene_index_lanes.hpp).
    static constexpr int index_lanes = 16;
    std::uint32_t closest_dense(BatchRoute way, Ray<Real>* rays, Hit<Real>* hits, int count, bool cull) const;
    std::uint32_t occluded_dense(BatchRoute way, const Ray<Real>* rays, int count) const;
    // Called only where Mesh::packed (under if constexpr): a trailing requires-clause on these
    // four, out of line and not templates, is more than clang 14 can match to its declaration.
    std::uint32_t intersect_through_index(Ray<Real>* rays, Hit<Real>* hits, int count, bool cull) const;
    std::uint32_t intersect_in_object_space(const Placement<Real>& instance, const Ray<Real>* rays, const Real* t_min,
                                            Real* t_max, std::uint32_t lanes, Hit<Real>* hits, std::uint32_t& tied,
                                            bool cull) const;
    std::uint32_t occluded_through_index(const Ray<Real>* rays, int count) const;
    std::uint32_t occludes_in_object_space(const Placement<Real>& instance, const Ray<Real>* rays, const Real* t_min,
                                           const Real* t_max, std::uint32_t lanes) const;
    struct ObjectSpaceRays;
    struct WorldSpaceRays;
    PRISM_FORCE_INLINE static std::uint32_t lanes_reaching(const typename Mesh::Leaf& leaf, const Ray<Real>* rays,
                                                               int n, std::uint32_t skip);
    template <class Packets>
    PRISM_FORCE_INLINE static typename Packets::LanePack lanes_t_max(const Ray<Real>* rays, int n);

    using Kind = typename Placement<Real>::Kind;
    using Direct = DirectTopLevel<Real, Mesh>;
    // The top level and every mesh share one index type, so one prepared ray serves both.
    using TraversalRay = typename Index::TraversalRay;
    using TriangleRay = typename Mesh::TriangleRay;

    const Mesh& mesh_at(std::uint32_t shape) const { return *meshes_[shape]; }

    // The meshes that share the world's space at every instant (no transformation, not
    // moving) go into one index over all their triangles, as Embree builds one BVH over a
    // scene's geometries: a ray then enters one tree instead of each overlapping mesh's tree
    // from the top level. A mesh that a MeshInstance places keeps its own index for the
    // instance to use. Brute force (PrimitiveList) has no levels to save, and Embree's shapes
    // (accel/embree.hpp) keep one mesh per object.
    // The same for the meshes merged_meshes chose, as the constructor has them.
    static std::uint32_t world_max_leaf_size(const scene::Scene& scene, const std::vector<bool>& merged) {
        constexpr std::size_t room_triangles = 64;
        std::size_t triangles = 0;
        for (std::size_t m = 0; m < scene.meshes.size(); ++m)
            if (merged[m]) triangles += scene.meshes[m].triangles.size();
        return scene::has_path_traced_camera(scene) && triangles <= room_triangles ? 2 : 0;
    }

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

    // intersect_indexed past the world meshes: the top level (direct or through its index);
    // `found` whether the world meshes were hit.
    PRISM_FORCE_INLINE bool intersect_top(Ray<Real>& ray, Hit<Real>& hit, bool found, const TraversalRay& traversal_ray,
                                              std::optional<TriangleRay>& world_triangle_ray, bool cull) const {
        if (direct_.chosen()) return direct_.closest(ray, hit, found, cull);
        if (top_objects_.empty()) return found;
        const auto& order = top_.primitive_indices();
        top_.traverse_closest(traversal_ray, ray.t_min, ray.t_max, [&](std::uint32_t first, std::uint32_t count, Real& t_max) {
            bool leaf_hit = false;
            for (std::uint32_t i = first; i < first + count; ++i) {
                const std::uint32_t object = top_objects_[order[i]];
                if (intersect_instance(placements_[object], ray, traversal_ray, world_triangle_ray, t_max, hit, cull)) {
                    hit.object = object;
                    leaf_hit = true;
                }
            }
            found |= leaf_hit;
            return leaf_hit;
        });
        return found;
    }
    PRISM_FORCE_INLINE bool occluded_direct(const Ray<Real>& ray) const {
        return direct_.occludes(ray) || planes_.occludes(ray);
    }

    // Whether the ray meets the box of a world-space index within its interval, by the same
    // conservative slab test as the BVHs (Ize's widened exit): a shadow ray's triangle set-up is
    // then made before the index is entered (eagerly, outside the kernel's leaf loop) and only
    // if it may reach a leaf, as the top level's box test did for a mesh in it.
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

    // Forced inline, as occludes below: the top level's leaf callbacks call them for every
    // object they reach, and with to_object forced inline GCC put both out of line (nm).
    PRISM_FORCE_INLINE bool intersect_instance(const Placement<Real>& instance, const Ray<Real>& ray,
                                                   const TraversalRay& traversal_ray,
                                                   std::optional<TriangleRay>& world_triangle_ray, Real& t_max,
                                                   Hit<Real>& hit, bool cull) const {
        if (instance.kind == Kind::mesh) {
            const auto& mesh = mesh_at(instance.shape);
            if (instance.template in_world_space<MotionBlur>()) {
                if (!world_triangle_ray) world_triangle_ray.emplace(ray);
                return mesh.intersect(ray, traversal_ray, *world_triangle_ray, t_max, hit, cull);
            }
            const Ray<Real> local = instance.template ray_to_object<MotionBlur>(ray);
            return mesh.intersect(local, t_max, hit, cull);
        }
        const Ray<Real> local = instance.template ray_to_object<MotionBlur>(ray);
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

    PRISM_FORCE_INLINE bool occludes(const Placement<Real>& instance, const Ray<Real>& ray, const TraversalRay& traversal_ray,
                  std::optional<TriangleRay>& world_triangle_ray, Real t_max) const {
        if (instance.kind == Kind::mesh && instance.template in_world_space<MotionBlur>()) {
            if (!world_triangle_ray) world_triangle_ray.emplace(ray);
            return mesh_at(instance.shape).occluded(ray, traversal_ray, *world_triangle_ray, t_max);
        }
        const Ray<Real> local = instance.template ray_to_object<MotionBlur>(ray);
        if (instance.kind == Kind::mesh) return mesh_at(instance.shape).occluded(local, t_max);
        Real t;
        return spheres_[instance.shape].intersect(local, ray.t_min, t_max, t) && t < t_max;
    }

    // A scene whose top level is tested without its index (direct spheres, or nothing but the
    // world-space meshes and planes) and whose world-space indices are each one leaf (at most N
    // triangles: the course's floors, walls and mirrors of two to six) is tested without the
    // TraversalRay: each index's leaf directly (TriangleMesh::intersect_leaf), then the spheres
    // and planes. The TraversalRay (three divisions, broadcast) and the root's box test were
    // a fifth of hw1 simple_reflectance's profile (a two-triangle floor and one sphere). An
    // index whose root holds up to four leaves is tested leaf by leaf too (intersect_root_leaves:
    // hw1 ocornellbox's ten wall triangles, where the TraversalRay, the root's test made twice
    // and the traversal were 15% of the profile; the hw7 Cornell boxes' three). The
    // hits are the index's: traversal of a single leaf tests that leaf, in the same slot order
    // with the same t_max; only a ray whose box test the index would fail is now tested too,
    // and the conservative box (Ize's widened exit) fails only rays that miss the triangles.
    // A scene with a top-level index keeps it, and its TraversalRay, but its world-space
    // indices of a few leaves are still tested leaf by leaf (intersect_indexed): hw2
    // horse_instanced's two-triangle floor had cost each camera ray a root test and a
    // traversal of their own, 7% of its instructions.
    void choose_direct_world_meshes() {
        for (WorldMeshes& group : world_meshes_) group.leaves = index_of(group).root_leaves();
        if (!top_objects_.empty() && !direct_.chosen()) return;
        bool several_leaves = false;
        for (const WorldMeshes& group : world_meshes_) {
            if (!group.leaves) return;
            several_leaves |= group.leaves->count > 1;
        }
        direct_form_ = true;
        several_leaves_ = several_leaves;
    }

    // The world-space meshes' leaves for intersect's direct path: hit or not, and hit filled as
    // intersect's loop over the indices fills it.
    // Several: some index has more than one (several_leaves_); without, the one-leaf code alone.
    template <bool Several>
    bool intersect_world_leaves(Ray<Real>& ray, Hit<Real>& hit, bool cull) const {
        if constexpr (Mesh::packed) {
            std::optional<TriangleRay> triangle_ray;  // made for the first leaf the ray may reach
            bool found = false;
            for (const WorldMeshes& group : world_meshes_) {
                const Mesh& index = index_of(group);
                const bool group_hit = intersect_root_leaves<Several>(index, *group.leaves, ray, triangle_ray, hit, cull);
                if (group_hit) {
                    if (group.index) group.attribute(index.source_triangle(hit.primitive), hit);
                    else hit.object = group.objects[0];
                    found = true;
                }
            }
            return found;
        } else {
            return false;  // root_leaves() is empty without packets: direct_form_ stays false
        }
    }

    // One index's closest hit from its root's few leaves, the hit its traversal finds. Each leaf
    // is tested up to the ray's own t_max, without the boxes' order: a leaf's test keeps its
    // closest candidate at or below t_max (later slots winning ties), so under a lower t_max a
    // nearer leaf's hit leaves a farther one, it is the same candidate where it passes, and the
    // strictly nearest of the leaves' hits is what any order of visits ends with. Only equal
    // nearest distances depend on the order (the later leaf wins), and the traversal orders
    // leaves by their boxes' entry distances: those rays (an edge shared by two leaves) are
    // handed to the traversal itself, from the state before any leaf.
    template <bool Several>
    PRISM_FORCE_INLINE static bool intersect_root_leaves(const Mesh& index, const typename Mesh::RootLeaves& leaves,
                                                             Ray<Real>& ray, std::optional<TriangleRay>& triangle_ray,
                                                             Hit<Real>& hit, bool cull) {
        const auto& first = leaves.leaf[0];
        if (!Several || leaves.count == 1) {
            if (leaves_box(first.box, ray)) return false;
            if (!triangle_ray) triangle_ray.emplace(ray);
            return index.intersect_leaf(ray, *triangle_ray, first, ray.t_max, hit, cull);
        }
        Real nearest = ray.t_max;
        Hit<Real> nearest_hit;
        bool found = false, tied = false;
        const std::uint32_t left = leaves.left_by(ray);
        for (int i = 0; i < leaves.count; ++i) {
            const auto& leaf = leaves.leaf[std::size_t(i)];
            if ((left >> i) & 1) continue;
            if (!triangle_ray) triangle_ray.emplace(ray);
            Real t = ray.t_max;
            Hit<Real> candidate = hit;
            if (!index.intersect_leaf(ray, *triangle_ray, leaf, t, candidate, cull)) continue;
            if (found && t == nearest) {
                tied = true;
                continue;
            }
            if (found && !(t < nearest)) continue;
            nearest = t;
            nearest_hit = candidate;
            found = true;
            tied = false;
        }
        if (tied) return index.intersect(ray, TraversalRay(ray), *triangle_ray, ray.t_max, hit, cull);
        if (!found) return false;
        ray.t_max = nearest;
        hit = nearest_hit;
        return true;
    }

    // occluded for direct_form_: the world meshes' leaves, then the direct top level and planes.
    PRISM_FORCE_INLINE bool occluded_without_index(const Ray<Real>& ray) const {
        return (!world_meshes_.empty() && (several_leaves_ ? occluded_world_leaves<true>(ray) : occluded_world_leaves<false>(ray))) ||
               occluded_direct(ray);
    }

    template <bool Several>
    bool occluded_world_leaves(const Ray<Real>& ray) const {
        if constexpr (Mesh::packed) {
            std::optional<TriangleRay> triangle_ray;
            for (const WorldMeshes& group : world_meshes_) {
                const Mesh& index = index_of(group);
                const std::uint32_t left = Several ? group.leaves->left_by(ray) : std::uint32_t(leaves_box(group.leaves->leaf[0].box, ray));
                for (int i = 0; i < (Several ? group.leaves->count : 1); ++i) {
                    const auto& leaf = group.leaves->leaf[std::size_t(i)];
                    if ((left >> i) & 1) continue;
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
        std::optional<typename Mesh::RootLeaves> leaves;  // the index's leaves, when its root has only a few

        // The hit on triangle `number` of the index (hit.primitive holds the index's slot)
        // as a hit on its own mesh: its object, its triangle there (the file's order, in which
        // its surface keeps them: SceneIndex::slot_order).
        // The part is the last whose first triangle is at most `number` (first_triangle[0] is
        // 0), found by a binary search whose steps are selects, not branches: a room's
        // closest hits fall on its walls at random, and std::upper_bound's branches
        // mispredicted (a tenth of SceneIndex::intersect_indexed's own samples on hw7
        // path_diffuse). The steps depend on the part count alone.
        void attribute(std::uint32_t number, Hit<Real>& hit) const {
            const std::uint32_t* base = first_triangle.data();
            for (std::size_t count = first_triangle.size(); count > 1;) {
                const std::size_t half = count / 2;
                base = base[half] <= number ? base + half : base;
                count -= half;
            }
            const std::size_t part = std::size_t(base - first_triangle.data());
            hit.object = objects[part];
            hit.primitive = number - first_triangle[part];
        }
    };
    // The index a world group is traversed through: its merged index, or its one part's own.
    const Mesh& index_of(const WorldMeshes& group) const { return group.index ? *group.index : mesh_at(group.objects[0]); }

    std::vector<std::optional<Mesh>> meshes_;  // none for a mesh merged into a world-space index
    std::vector<Placement<Real>> placements_;
    std::vector<SphereShape<Real>> spheres_;
    std::vector<WorldMeshes> world_meshes_;
    std::vector<std::uint32_t> top_objects_;  // the top level's primitives: the objects not merged
    Direct direct_;  // the top level without its index, where chosen
    bool direct_form_ = false;  // no TraversalRay: the top level direct, the world meshes' leaves too
    bool several_leaves_ = false;  // some world-space index of the direct form has a root of several leaves
    PlaneSet<Real> planes_;
    Aabb<Real> bounds_;
    Index top_;
};

}  // namespace prism

#include <prism/geometry/scene_index_lanes.hpp>
