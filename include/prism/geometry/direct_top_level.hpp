// The top level of a scene of a few objects (the course's scenes of 1 to 8 spheres, and small
// transformed plates), tested object after object without the top-level index: the
// traversal's prepared ray (three divisions, broadcast) and its node test cost more than the
// spheres (hw2 mirror_room: the prepared ray alone was 15% of the time). Each object is tested
// as the index's leaf tests it, so the hits are the same; only two spheres hit at exactly the
// same distance could resolve otherwise (the later one tested wins in both).
// Up to 8, the objects' culls in one SIMD pass (may_hit): tested one by one, 5 and 6
// untransformed spheres (hw1 spheres_with_plane, spheres.json) had cost more than the index's
// one 8-wide box test (1.04-1.05 of its CPU time, whole3).
// Planes are not here: the index tests them after these (geometry/planes.hpp).
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/geometry/aabb.hpp>
#include <prism/geometry/hit.hpp>
#include <prism/geometry/placement.hpp>
#include <prism/geometry/ray_lanes.hpp>
#include <prism/geometry/sphere.hpp>
#include <prism/scene/scene.hpp>
#include <prism/simd/pack.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <type_traits>
#include <vector>

namespace prism {

// Whether the ray starts outside the box beyond one of its faces and does not move towards
// it (a floor's rays that start above it and go up: most shadow and reflected rays), with
// t_min >= 0. The index's slab test rejects every such ray without a division: the far
// plane's distance (face - origin) / direction is negative, or -inf for a zero direction
// of either sign, or the near plane's +inf, so the exit falls below the entry. (Only a
// distance that underflows to -0, an origin within a subnormal's width of the face, would
// pass that test; the ray then starts on the box and the leaf test decides, as here.)
template <Scalar Real>
PRISM_FORCE_INLINE inline bool leaves_box(const Aabb<Real>& box, const Ray<Real>& ray) {
    bool away = false;
    for (int axis = 0; axis < 3; ++axis)
        away |= unsigned(ray.origin[axis] > box.max[axis] && ray.direction[axis] >= 0) |
                unsigned(ray.origin[axis] < box.min[axis] && ray.direction[axis] <= 0);  // no branch
    return away && ray.t_min >= 0;
}

// `Mesh`: the index's TriangleMesh, whose single leaf a direct mesh tests.
template <Scalar Real, class Mesh>
class DirectTopLevel {
public:
    static constexpr int width = 8;

    DirectTopLevel() = default;
    // Holds pointers to the index's meshes: moved with it, never copied.
    DirectTopLevel(const DirectTopLevel&) = delete;
    DirectTopLevel& operator=(const DirectTopLevel&) = delete;
    DirectTopLevel(DirectTopLevel&&) = default;
    DirectTopLevel& operator=(DirectTopLevel&&) = default;

    // Takes the top level's objects if there are at most `width` and every mesh among them is
    // one leaf; else stays unchosen. `meshes[shape]`: the index's mesh `shape`. A moving object
    // (motion blur) is tested at the ray's instant, as the index's leaf tests it, inside a
    // bound around its sweep: hw3 cornellbox_dynamic's one moving sphere had sent its ten
    // walls and two spheres through the top-level index.
    void choose(const scene::Scene& scene, std::span<const std::uint32_t> top_objects,
                std::span<const Placement<Real>> placements, std::span<const SphereShape<Real>> spheres,
                std::span<const std::optional<Mesh>> meshes) {
        using Kind = typename Placement<Real>::Kind;
        if (top_objects.empty() || top_objects.size() > std::size_t(width)) return;
        const std::size_t first_sphere = scene.meshes.size() + scene.mesh_instances.size();
        std::vector<DirectSphere> chosen;
        std::vector<DirectMesh> chosen_meshes;
        Bounds bounds;
        for (const std::uint32_t object : top_objects) {
            const Placement<Real>& placement = placements[object];
            if (placement.kind == Kind::mesh) {
                const Mesh& mesh = *meshes[placement.shape];
                const std::optional<typename Mesh::Leaf> leaf = mesh.single_leaf();
                if (!leaf) return;
                chosen_meshes.push_back({object, *leaf, &mesh, placement});
                continue;
            }
            DirectSphere direct;
            direct.object = object;
            direct.shape = spheres[placement.shape];
            direct.placement = placement;
            if (placement.moving) {
                // Bounded as a mesh is, around its box, which covers the sweep.
                direct.map = DirectSphere::Map::moving;
                set_around_box(bounds, chosen.size(), placement.world_bounds);
                chosen.push_back(direct);
                continue;
            }
            if (placement.transformed) {
                direct.map = Mat3<Real>(placement.world_to_object) == Mat3<Real>(1) ? DirectSphere::Map::translation
                                                                                    : DirectSphere::Map::matrix;
                direct.translation = Vec3<Real>(placement.world_to_object[3]);
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
        // box (conservative: Placement rounds it outwards), so that rays passing far from a
        // small transformed mesh are culled before the object-space transform and leaf test.
        // Without it, hw2 simple_transform (two rotated meshes, a sphere) took 1.3x the CPU
        // time of the index, whose world boxes had culled those rays.
        for (std::size_t m = 0; m < chosen_meshes.size(); ++m)
            set_around_box(bounds, chosen.size() + m, chosen_meshes[m].placement.world_bounds);
        spheres_ = std::move(chosen);
        meshes_ = std::move(chosen_meshes);
        bounds_ = bounds;
        chosen_ = true;
    }

    bool chosen() const { return chosen_; }
    bool has_spheres() const { return !spheres_.empty(); }
    bool has_meshes() const { return !meshes_.empty(); }

    // The closest hit among the objects, in their order (spheres, then meshes), below ray.t_max
    // (lowered to it, hit filled); `found`: something nearer was hit already.
    PRISM_FORCE_INLINE bool closest(Ray<Real>& ray, Hit<Real>& hit, bool found, bool cull) const {
        const Candidates may = candidates(ray);
        for (std::uint32_t lanes = may.spheres; lanes != 0; lanes &= lanes - 1) {
            const DirectSphere& sphere = spheres_[std::size_t(std::countr_zero(lanes))];
            Real t;
            if (!hit_sphere(sphere, ray, ray.t_max, t)) continue;
            ray.t_max = t;
            hit.t = t;
            hit.primitive = 0;
            hit.b1 = hit.b2 = 0;  // a sphere's whole record, as the index's leaves write it
            hit.object = sphere.object;
            found = true;
        }
        if constexpr (Mesh::packed) {
            for (std::uint32_t lanes = may.meshes; lanes != 0; lanes &= lanes - 1) {
                const DirectMesh& direct = meshes_[std::size_t(std::countr_zero(lanes))];
                const std::optional<Ray<Real>> local = mesh_ray(direct, ray);
                if (!local) continue;
                const typename Mesh::TriangleRay triangle_ray(*local);
                if (direct.mesh->intersect_leaf(*local, triangle_ray, direct.leaf, ray.t_max, hit, cull)) {
                    hit.object = direct.object;
                    found = true;
                }
            }
        }
        return found;
    }

    // Whether one of the objects lies in (ray.t_min, ray.t_max).
    bool occludes(const Ray<Real>& ray) const {
        const Candidates may = candidates(ray);
        for (std::uint32_t lanes = may.spheres; lanes != 0; lanes &= lanes - 1) {
            const DirectSphere& sphere = spheres_[std::size_t(std::countr_zero(lanes))];
            Real t;
            if (hit_sphere(sphere, ray, ray.t_max, t) && t < ray.t_max) return true;
        }
        if constexpr (Mesh::packed) {
            for (std::uint32_t lanes = may.meshes; lanes != 0; lanes &= lanes - 1) {
                const DirectMesh& direct = meshes_[std::size_t(std::countr_zero(lanes))];
                const std::optional<Ray<Real>> local = mesh_ray(direct, ray);
                if (local && direct.mesh->occluded_leaf(*local, typename Mesh::TriangleRay(*local), direct.leaf, ray.t_max))
                    return true;
            }
        }
        return false;
    }

    // The spheres of the direct top level against up to width rays, one in each lane
    // (a batch's leaf lanes): sphere after sphere in closest's order, each lane's may_hit
    // lane and SphereShape::intersect computed with their operations in their order, so each
    // lane finds what closest's sphere loop finds for its ray (its t_max lowered, its
    // hit's t, primitive and object set, its bit of `found` set). Spheres mapped by a matrix
    // (ellipsoids) and transformed spheres that move are tested ray by ray; a moving sphere in
    // world space takes the lanes, each ray's origin moved back. AnyHit: occludes' question
    // instead, a hit below t_max (open) setting the lane's bit of `found`, and nothing else written.
    template <bool AnyHit = false>
    void intersect_spheres_lanes(std::conditional_t<AnyHit, const Ray<Real>*, Ray<Real>*> rays, Hit<Real>* hits,
                                        int count, std::uint32_t& found) const {
        static_assert(width == 8);
        Lanes fields[width];
        rays_as_lanes(rays, count, fields);
        const Lanes o[3] = {fields[0], fields[1], fields[2]};
        const Lanes d[3] = {fields[3], fields[4], fields[5]};
        const Lanes t_min = fields[6];
        Lanes t_max = fields[7];
        alignas(64) Real limits[width];  // t_max's lanes, where a sphere hit lowers them
        if constexpr (!AnyHit) t_max.store(limits);
        const Lanes zero = Lanes::broadcast(0);
        const auto dot = [](const Lanes* x, const Lanes* y) { return (x[0] * y[0] + x[1] * y[1]) + x[2] * y[2]; };
        const Lanes a = dot(d, d);  // glm::dot(direction, direction), as may_hit and the sphere test take it
        const std::uint32_t rays_present = (std::uint32_t(1) << count) - 1;
        const std::uint32_t starts_ahead = (t_min >= zero).bits();
        const Lanes slack = Lanes::broadcast(16 * std::numeric_limits<Real>::epsilon());
        for (std::size_t s = 0; s < spheres_.size(); ++s) {
            // may_hit's lane s, for every ray.
            Lanes to_bound[3];
            for (int axis = 0; axis < 3; ++axis)
                to_bound[axis] = o[axis] - Lanes::broadcast(bounds_.center[axis][s]);
            const Lanes along = dot(to_bound, d), distance_squared = dot(to_bound, to_bound);
            const Lanes radius_squared = Lanes::broadcast(bounds_.radius_squared[s]);
            const std::uint32_t leaving = ((zero <= along) & (radius_squared < distance_squared)).bits() & starts_ahead;
            const std::uint32_t near =
                (a * distance_squared - along * along <= a * (radius_squared + slack * distance_squared)).bits();
            std::uint32_t may = near & ~leaving & rays_present;
            if constexpr (AnyHit) may &= ~found;
            if (may == 0) continue;

            const DirectSphere& sphere = spheres_[s];
            if (sphere.map == DirectSphere::Map::matrix || (sphere.map == DirectSphere::Map::moving && sphere.placement.transformed)) {
                for (; may != 0; may &= may - 1) {
                    const int i = std::countr_zero(may);
                    Real t;
                    if (!hit_sphere(sphere, rays[i], rays[i].t_max, t)) continue;
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
                    for (int i = 0; i < count; ++i) limits[i] = rays[i].t_max;
                    t_max = Lanes::load(limits);
                }
                continue;
            }
            // SphereShape::intersect, from the origin hit_sphere gives it.
            const SphereShape<Real>& shape = sphere.shape;
            Lanes oc[3];
            if (sphere.map == DirectSphere::Map::moving) {
                // In world space here: as ray_to_object, each ray's origin moved back by the
                // motion at its instant.
                alignas(64) Real instants[width];
                for (int lane = 0; lane < width; ++lane) instants[lane] = rays[lane < count ? lane : 0].time;
                const Lanes time = Lanes::load(instants);
                for (int axis = 0; axis < 3; ++axis)
                    oc[axis] = (o[axis] - Lanes::broadcast(sphere.placement.motion[axis]) * time) - Lanes::broadcast(shape.center[axis]);
            } else {
                for (int axis = 0; axis < 3; ++axis) {
                    const Lanes origin = sphere.map == DirectSphere::Map::translation
                                                  ? o[axis] + Lanes::broadcast(sphere.translation[axis])
                                                  : o[axis];
                    oc[axis] = origin - Lanes::broadcast(shape.center[axis]);
                }
            }
            const Lanes r2 = Lanes::broadcast(shape.radius * shape.radius);
            const Lanes half_b = dot(oc, d);
            const Lanes c = dot(oc, oc) - r2;
            may &= ~(((half_b >= zero) & (c > zero)).bits() & starts_ahead);
            const Lanes scale = half_b / a;
            Lanes perpendicular[3];
            for (int axis = 0; axis < 3; ++axis) perpendicular[axis] = oc[axis] - scale * d[axis];
            const Lanes discriminant_over_a = r2 - dot(perpendicular, perpendicular);
            may &= ~(discriminant_over_a < zero).bits();
            if (may == 0) continue;
            const Lanes root = sqrt(a * discriminant_over_a);
            const Lanes q = select(half_b >= zero, -(half_b + root), -(half_b - root));
            const auto q_zero = q == zero;
            const Lanes t0 = select(q_zero, zero, c / q), t1 = select(q_zero, zero, q / a);
            const auto swap = t0 > t1;
            const Lanes nearer = select(swap, t1, t0), farther = select(swap, t0, t1);
            const auto nearer_in = (nearer > t_min) & (nearer <= t_max);
            const auto farther_in = (farther > t_min) & (farther <= t_max);
            const Lanes t = select(nearer_in, nearer, farther);
            if constexpr (AnyHit) {
                found |= ((nearer_in | farther_in) & (t < t_max)).bits() & may;
            } else {
                std::uint32_t taken = (nearer_in | farther_in).bits() & may;
                if (taken == 0) continue;
                alignas(64) Real t_lanes[width];
                t.store(t_lanes);
                for (; taken != 0; taken &= taken - 1) {
                    const int i = std::countr_zero(taken);
                    rays[i].t_max = limits[i] = t_lanes[i];
                    hits[i].t = t_lanes[i];
                    hits[i].primitive = 0;
                    hits[i].b1 = hits[i].b2 = 0;
                    hits[i].object = sphere.object;
                    found |= std::uint32_t(1) << i;
                }
                t_max = Lanes::load(limits);
            }
        }
    }

private:
    using Lanes = simd::Pack<Real, width>;

    // Each object on cache lines of its own (alignas(64), so the vector's block is too): with
    // the small heap block next to data the render threads write, hw2 simple_reflectance's
    // shadow rays stalled on reading it at 2 threads (1.25 of base's CPU time, 0.91 at 1 thread).
    struct alignas(64) DirectSphere {
        std::uint32_t object = 0;
        // How the ray reaches object space: unchanged, moved by `translation` (a transform that
        // only translates: the matrix product's answer, ox + tx with zero terms, bit for bit),
        // by the placement's matrix, or (moving) to where the sphere is at the ray's instant.
        enum class Map : std::uint8_t { none, translation, matrix, moving } map = Map::none;
        Vec3<Real> translation{0};
        SphereShape<Real> shape;
        Placement<Real> placement;
    };
    // A mesh of the top level small enough for one leaf (a transformed floor or plate of a few
    // triangles): the ray is taken to its object space and the leaf tested there, as the
    // mesh's own index would after the top level's box test. Rays that leave the leaf's box by
    // a face are culled in object space first, as that index's slab test rejects them; only
    // rays the world box alone would have stopped are tested too, and they miss.
    struct alignas(64) DirectMesh {
        std::uint32_t object = 0;
        typename Mesh::Leaf leaf;
        const Mesh* mesh = nullptr;
        Placement<Real> placement;
    };
    // Around each object, lane by lane, a world-space sphere widened so that may_hit never
    // rejects a ray the object-space test hits: it culls as the index's box did. Lanes past the
    // last object are masked off.
    struct Bounds {
        alignas(64) Real center[3][width] = {};
        alignas(64) Real radius_squared[width] = {};
        std::uint32_t lanes = 0;

        void set(std::size_t lane, const Vec3<Real>& sphere_center, double radius) {
            for (int axis = 0; axis < 3; ++axis) center[axis][lane] = sphere_center[axis];
            radius_squared[lane] = Real(radius * radius);
            lanes |= std::uint32_t(1) << lane;
        }
    };

    // Lane `lane`'s sphere around a world box: the half diagonal, plus how far rounding moved
    // the centre, widened by 0.1% as a sphere's bound is.
    static void set_around_box(Bounds& bounds, std::size_t lane, const Aabb<Real>& box) {
        const glm::dvec3 low(box.min), high(box.max);
        const glm::dvec3 exact_center = 0.5 * (low + high);
        const Vec3<Real> center(exact_center);
        const double radius = (0.5 * glm::length(high - low) + glm::length(glm::dvec3(center) - exact_center)) * (1 + 1e-3);
        bounds.set(lane, center, radius);
    }

    // Which direct objects the ray may meet (bit i for sphere i, then the meshes' bits after
    // the spheres' as choose lays them out): lane by lane, false only where
    // it surely misses, starting outside and leaving, or passing wider than the radius
    // (a |oc|^2 - b^2 > a r^2, no division). The rounded oc, b and products are off by at most
    // 8 epsilon a |oc|^2 in all (the cancellation when the ray aims at the centre); the test
    // allows twice that. Each lane computes what the scalar dot products compute, in their order.
    PRISM_FORCE_INLINE std::uint32_t may_hit(const Ray<Real>& ray) const {
        const Bounds& bounds = bounds_;
        Lanes oc[3];
        for (int axis = 0; axis < 3; ++axis)
            oc[axis] = Lanes::broadcast(ray.origin[axis]) - Lanes::load(bounds.center[axis]);
        const Lanes dx = Lanes::broadcast(ray.direction.x), dy = Lanes::broadcast(ray.direction.y),
                         dz = Lanes::broadcast(ray.direction.z);
        const Lanes b = (oc[0] * dx + oc[1] * dy) + oc[2] * dz;
        const Lanes distance_squared = (oc[0] * oc[0] + oc[1] * oc[1]) + oc[2] * oc[2];
        const Lanes radius_squared = Lanes::load(bounds.radius_squared);
        std::uint32_t leaving = 0;
        if (ray.t_min >= 0) leaving = ((Lanes::broadcast(Real(0)) <= b) & (radius_squared < distance_squared)).bits();
        const Lanes a = Lanes::broadcast(glm::dot(ray.direction, ray.direction));
        const Lanes slack = Lanes::broadcast(16 * std::numeric_limits<Real>::epsilon());
        const std::uint32_t near = (a * distance_squared - b * b <= a * (radius_squared + slack * distance_squared)).bits();
        return near & ~leaving & bounds.lanes;
    }

    // Whether the ray meets `sphere` in (ray.t_min, t_max], tested in object space as the
    // index's leaf tests it; for the spheres may_hit lets through.
    PRISM_FORCE_INLINE static bool hit_sphere(const DirectSphere& sphere, const Ray<Real>& ray, Real t_max, Real& t) {
        switch (sphere.map) {
            case DirectSphere::Map::none: return sphere.shape.intersect(ray, ray.t_min, t_max, t);
            case DirectSphere::Map::translation: {
                Ray<Real> local = ray;
                local.origin = ray.origin + sphere.translation;
                return sphere.shape.intersect(local, ray.t_min, t_max, t);
            }
            case DirectSphere::Map::matrix: break;
            case DirectSphere::Map::moving:
                return sphere.shape.intersect(sphere.placement.template ray_to_object<true>(ray), ray.t_min, t_max, t);
        }
        return sphere.shape.intersect(sphere.placement.to_object(ray), ray.t_min, t_max, t);
    }

    // The objects may_hit lets through, as bits of spheres_ and of meshes_.
    struct Candidates {
        std::uint32_t spheres = 0, meshes = 0;
    };
    PRISM_FORCE_INLINE Candidates candidates(const Ray<Real>& ray) const {
        if (bounds_.lanes == 0) return {};
        const std::uint32_t may = may_hit(ray);
        const std::size_t spheres = spheres_.size();
        return {may & ((std::uint32_t(1) << spheres) - 1), may >> spheres};
    }
    // A direct mesh's ray in its object space, or none where its leaf's box culls it there.
    PRISM_FORCE_INLINE static std::optional<Ray<Real>> mesh_ray(const DirectMesh& direct, const Ray<Real>& ray) {
        const Ray<Real> local = direct.placement.template ray_to_object<true>(ray);
        if (leaves_box(direct.leaf.box, local)) return std::nullopt;
        return local;
    }

    std::vector<DirectSphere> spheres_;
    std::vector<DirectMesh> meshes_;
    Bounds bounds_;
    bool chosen_ = false;
};

}  // namespace prism
