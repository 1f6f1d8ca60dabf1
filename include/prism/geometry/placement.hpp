// Where an object of a scene is: which shape it places (a mesh or a sphere of the scene), how
// world space maps into its object space, and how it moves over the shutter. The index reads
// it to take rays into object space; the surfaces read it to take hits back out. A MeshInstance
// costs one placement, never a copy of its mesh or of the mesh's index.
// With MotionBlur, an object with a MotionBlur translation m is at M p + m t at shutter instant
// t: rays are moved back by m t before entering its object space, and its world box covers the
// whole sweep (the boxes at t = 0 and t = 1 together, exact for a translation).
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/geometry/aabb.hpp>
#include <prism/geometry/ray.hpp>
#include <prism/geometry/sphere.hpp>
#include <prism/math/floating_point.hpp>
#include <prism/math/transform.hpp>
#include <prism/scene/scene.hpp>

#include <cstdint>
#include <vector>

namespace prism {

template <Scalar Real>
struct Placement {
    enum class Kind : std::uint8_t { mesh, sphere };

    Kind kind = Kind::mesh;
    bool transformed = false;
    bool moving = false;       // only with MotionBlur
    std::uint32_t shape = 0;   // the scene's mesh or sphere it places
    Mat4<Real> world_to_object{1};
    Mat3<Real> world_to_object_linear{1};
    Vec3<Real> motion{0};
    Aabb<Real> world_bounds;   // covers the sweep of a moving object

    // Placed by `transform` (the scene's, in double) with `object_bounds` in object space, moving
    // by `motion` when the renderer has motion blur.
    static Placement place(Kind kind, std::uint32_t shape, const glm::dmat4& transform, const Aabb<Real>& object_bounds,
                           const glm::dvec3& motion, bool motion_blur) {
        Placement placement;
        placement.kind = kind;
        placement.shape = shape;
        placement.transformed = transform != glm::dmat4(1.0);
        if (placement.transformed) {
            // Inverses are taken in double from the file's values, then rounded once to Real.
            const glm::dmat4 inverse = glm::inverse(transform);
            placement.world_to_object = Mat4<Real>(inverse);
            placement.world_to_object_linear = Mat3<Real>(glm::dmat3(inverse));
            for (int c = 0; c < 8; ++c)
                placement.world_bounds.extend(Vec3<Real>(transform * glm::dvec4(glm::dvec3(object_bounds.corner(c)), 1.0)));
            // The corners are rounded to nearest, so the box could fall inside the transformed
            // object by half an ulp: rays through a silhouette vertex on it were lost (found by
            // the direct test of test_small_scenes). One ulp outwards keeps it conservative.
            widen_by_ulp(placement.world_bounds);
        } else {
            placement.world_bounds = object_bounds;
        }
        if (motion_blur && motion != glm::dvec3(0.0)) {
            placement.moving = true;
            placement.motion = Vec3<Real>(motion);
            Aabb<Real> swept = placement.world_bounds;
            swept.extend(Aabb<Real>{swept.min + placement.motion, swept.max + placement.motion});
            // The sweep's corners are rounded sums: one ulp outwards keeps the box conservative.
            widen_by_ulp(swept);
            placement.world_bounds = swept;
        }
        return placement;
    }

    // Forced inline: the direct spheres' test calls it for every ray a transformed sphere may
    // meet, and GCC left it out of line there (8% of hw2 spheres.json).
    PRISM_FORCE_INLINE Vec3<Real> to_object(const Vec3<Real>& p) const { return transform_point(world_to_object, p); }
    // The direction is transformed but not renormalised, so t means the same in both spaces.
    PRISM_FORCE_INLINE Ray<Real> to_object(const Ray<Real>& ray) const {
        return {to_object(ray.origin), transform_direction(world_to_object_linear, ray.direction), ray.t_min, ray.t_max,
                ray.time};
    }

    // Where a moving object has gone by the instant `time`; zero without motion blur.
    template <bool MotionBlur>
    PRISM_FORCE_INLINE Vec3<Real> displacement(Real time) const {
        if constexpr (MotionBlur) {
            if (moving) return motion * time;
        }
        return Vec3<Real>(0);
    }

    // The ray in object space, at the ray's instant for a moving object. Forced inline as
    // to_object is (the top level's leaf and the direct meshes call it).
    template <bool MotionBlur>
    PRISM_FORCE_INLINE Ray<Real> ray_to_object(const Ray<Real>& ray) const {
        if constexpr (MotionBlur) {
            if (moving) {
                Ray<Real> unmoved = ray;
                unmoved.origin -= motion * ray.time;
                return transformed ? to_object(unmoved) : unmoved;
            }
        }
        return transformed ? to_object(ray) : ray;
    }

    // Whether the object's space is the world's at every instant: then a mesh it places reuses
    // the world ray's set-up (the same ray, bit for bit) instead of preparing its own.
    template <bool MotionBlur>
    bool in_world_space() const {
        if constexpr (MotionBlur) {
            if (moving) return false;
        }
        return !transformed;
    }

private:
    static void widen_by_ulp(Aabb<Real>& box) {
        for (int axis = 0; axis < 3; ++axis) {
            box.min[axis] = next_down(box.min[axis]);
            box.max[axis] = next_up(box.max[axis]);
        }
    }
};

// The scene's objects in prism's numbering (Hit::object): its meshes, then its mesh instances,
// then its spheres; the planes come after them (PlaneSet). `mesh_bounds(m)`: mesh m's box in
// its object space. Both an index and the surfaces that pair with it number objects so.
template <Scalar Real, class MeshBounds>
std::vector<Placement<Real>> place_objects(const scene::Scene& scene, const MeshBounds& mesh_bounds, bool motion_blur) {
    using Kind = typename Placement<Real>::Kind;
    std::vector<Placement<Real>> placements;
    placements.reserve(scene.meshes.size() + scene.mesh_instances.size() + scene.spheres.size());
    for (std::size_t m = 0; m < scene.meshes.size(); ++m)
        placements.push_back(Placement<Real>::place(Kind::mesh, std::uint32_t(m), scene.meshes[m].transform, mesh_bounds(m),
                                                    scene.meshes[m].motion, motion_blur));
    for (const auto& instance : scene.mesh_instances)
        placements.push_back(Placement<Real>::place(Kind::mesh, std::uint32_t(instance.base_mesh), instance.transform,
                                                    mesh_bounds(instance.base_mesh), instance.motion, motion_blur));
    for (std::size_t s = 0; s < scene.spheres.size(); ++s) {
        const scene::Sphere& sphere = scene.spheres[s];
        const SphereShape<Real> shape{Vec3<Real>(sphere.center), Real(sphere.radius)};
        placements.push_back(
            Placement<Real>::place(Kind::sphere, std::uint32_t(s), sphere.transform, shape.bounds(), sphere.motion, motion_blur));
    }
    return placements;
}

}  // namespace prism
