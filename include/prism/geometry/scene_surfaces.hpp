// What a hit means, for every object of a scene: the surface point (normals, texture
// coordinates and tangents, the object's material and textures), the radiance an object light
// emits, and the origin of a ray leaving the surface by the hit point's floating-point error
// bound (geometry/surface_error.hpp) instead of a scene-tuned epsilon. It holds no index: prism's
// own (SceneIndex) and Embree's (accel/embree.hpp) find the hits, and either pairs with one of
// these. Objects are numbered as place_objects numbers them (meshes, mesh instances, spheres),
// planes after them.
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/geometry/hit.hpp>
#include <prism/geometry/mesh_surface.hpp>
#include <prism/geometry/placement.hpp>
#include <prism/geometry/planes.hpp>
#include <prism/geometry/sphere.hpp>
#include <prism/geometry/surface_error.hpp>
#include <prism/math/transform.hpp>
#include <prism/scene/scene.hpp>

#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

namespace prism {

template <Scalar Real, class Intersector, bool MotionBlur = false>
class SceneSurfaces {
public:
    using Kind = typename Placement<Real>::Kind;

    // `placements`: the scene's objects as the index placed them (place_objects); `order(m)`:
    // the slot order in which the index names mesh m's triangles (empty: the file's).
    template <class MeshOrder>
    SceneSurfaces(const scene::Scene& scene, std::span<const Placement<Real>> placements, MeshOrder order) {
        meshes_.reserve(scene.meshes.size());
        for (std::size_t m = 0; m < scene.meshes.size(); ++m) meshes_.emplace_back(scene.meshes[m], order(m));
        for (const auto& sphere : scene.spheres) spheres_.push_back({Vec3<Real>(sphere.center), Real(sphere.radius)});
        instances_.reserve(placements.size());
        const auto add = [&](std::size_t material, const std::vector<std::size_t>& textures, const glm::dmat4& transform,
                             const glm::dvec3& radiance) {
            Instance instance;
            static_cast<Placement<Real>&>(instance) = placements[instances_.size()];
            instance.material = std::uint32_t(material);
            instance.textures = add_texture_list(textures);
            if (instance.transformed) {
                const glm::dmat4 inverse = glm::inverse(transform);
                instance.normal_to_world = Mat3<Real>(glm::transpose(glm::dmat3(inverse)));
                instance.object_to_world_linear = Mat3<Real>(glm::dmat3(transform));
                instance.transform = std::uint32_t(transforms_.size());
                transforms_.emplace_back(transform);
            }
            instances_.push_back(instance);
            emitted_.emplace_back(radiance);
        };
        for (const auto& mesh : scene.meshes) add(mesh.material, mesh.textures, mesh.transform, mesh.radiance);
        for (const auto& instance : scene.mesh_instances)
            add(instance.material, instance.textures, instance.transform, scene.meshes[instance.base_mesh].radiance);
        for (const auto& sphere : scene.spheres) add(sphere.material, sphere.textures, sphere.transform, sphere.radiance);
        for (const auto& plane : scene.planes) {
            planes_.push_back(PlaneShape<Real>::of(plane));
            plane_materials_.push_back(std::uint32_t(plane.material));
            plane_textures_.push_back(add_texture_list(plane.textures));
        }
    }

    std::size_t instance_count() const { return instances_.size(); }
    std::size_t triangle_count() const {
        std::size_t total = 0;
        for (const auto& instance : instances_)
            if (instance.kind == Kind::mesh) total += meshes_[instance.shape].triangle_count();
        return total;
    }

    // The radiance object `object` (Hit::object) emits from its surface: a LightMesh's or
    // LightSphere's (and a LightMesh instance's), zero for every other object and for planes.
    Vec3<Real> emitted(std::uint32_t object) const { return object < emitted_.size() ? emitted_[object] : Vec3<Real>(0); }
    // Which triangle of an emitting mesh (or mesh instance) `hit` found, as the file numbers
    // them (LightMesh's order): a light's density of reaching the point depends on its triangle.
    std::uint32_t emitting_triangle(const Hit<Real>& hit) const {
        if (hit.object >= instances_.size() || instances_[hit.object].kind != Kind::mesh) return 0;
        return meshes_[instances_[hit.object].shape].file_triangle(hit.primitive);
    }

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
    PRISM_FORCE_INLINE SurfacePoint<Real> surface(const Ray<Real>& ray, const Hit<Real>& hit,
                                                      bool spawn_point = true) const {
        return surface_of<false>(ray, hit, spawn_point);
    }

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
    PRISM_FORCE_INLINE int spawn_side(const SurfacePoint<Real>& point, const Vec3<Real>& direction) const {
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

    // For an index from outside (accel/embree.hpp), which finds a primitive but leaves prism to
    // compute the hit: one primitive of one object tested as prism's own index tests it
    // (world-space ray taken to object space, the triangle test, the sphere test). `primitive`
    // is a triangle's slot (the file's order for such an index); spheres ignore it. On a hit in
    // (t_min, t_max] it lowers ray.t_max and fills hit.
    bool intersect_primitive(std::uint32_t object, std::uint32_t primitive, Ray<Real>& ray, Hit<Real>& hit) const {
        const Instance& instance = instances_[object];
        const Ray<Real> local = instance.template ray_to_object<MotionBlur>(ray);
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
    // Whether a rule that culls (either: they differ only for planes) skips this triangle of
    // this object for this (world-space) ray, decided as prism's own index decides it: meshes by
    // their winding in object space.
    bool culled(std::uint32_t object, std::uint32_t primitive, const Ray<Real>& ray) const {
        const Instance& instance = instances_[object];
        if (instance.kind != Kind::mesh) return false;
        return meshes_[instance.shape].faces_away(primitive, instance.template ray_to_object<MotionBlur>(ray).direction);
    }
    const Placement<Real>& placement(std::uint32_t object) const { return instances_[object]; }

private:
    // A placement and what shading adds to it.
    struct Instance : Placement<Real> {
        std::uint32_t material = 0;
        std::uint32_t textures = 0;   // index into texture_lists_
        std::uint32_t transform = 0;  // index into transforms_, when transformed
        Mat3<Real> normal_to_world{1};
        Mat3<Real> object_to_world_linear{1};
    };

    template <bool Parametrised>
    PRISM_FORCE_INLINE SurfacePoint<Real> surface_of(const Ray<Real>& ray, const Hit<Real>& hit,
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
        const Vec3<Real> unmoved = point.position - instance.template displacement<MotionBlur>(ray.time);
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

    std::uint32_t add_texture_list(const std::vector<std::size_t>& textures) {
        if (textures.empty()) return 0;
        texture_lists_.emplace_back(textures.begin(), textures.end());
        return std::uint32_t(texture_lists_.size() - 1);
    }

    std::vector<Instance> instances_;
    std::vector<InstanceTransforms<Real>> transforms_;
    std::vector<MeshSurface<Real, Intersector>> meshes_;
    std::vector<SphereShape<Real>> spheres_;
    std::vector<PlaneShape<Real>> planes_;
    std::vector<std::uint32_t> plane_materials_;
    std::vector<std::uint32_t> plane_textures_;
    // Each object's texture indices; entry 0 is the empty list that untextured objects share.
    std::vector<std::vector<std::uint32_t>> texture_lists_{1};
    std::vector<Vec3<Real>> emitted_;  // per object, in place_objects' order
};

}  // namespace prism
