// All the geometry of a scene in the renderer's precision: meshes (each with its own index),
// spheres and planes, placed by instances under a top-level index. This is the two-level
// hierarchy: a MeshInstance costs one instance record, never a copy of its mesh or its BVH.
// It satisfies Accelerator: intersect (closest hit) and occluded (any hit).
#pragma once

#include <prism/accel/accelerator.hpp>
#include <prism/geometry/hit.hpp>
#include <prism/geometry/sphere.hpp>
#include <prism/geometry/triangle_mesh.hpp>
#include <prism/scene/scene.hpp>

#include <cstdint>
#include <vector>

namespace prism {

template <Scalar Real>
struct PlaneShape {
    Vec3<Real> point{0};
    Vec3<Real> normal{0, 1, 0};  // unit

    bool intersect(const Ray<Real>& ray, Real t_min, Real t_max, Real& t_hit) const {
        const Real denominator = glm::dot(ray.direction, normal);
        if (denominator == 0) return false;
        const Real t = glm::dot(point - ray.origin, normal) / denominator;
        if (!(t > t_min && t <= t_max)) return false;
        t_hit = t;
        return true;
    }
};

template <Scalar Real, class Policy>
    requires AccelerationPolicy<Policy, Real>
class SceneGeometry {
public:
    using Index = typename Policy::template Index<Real>;

    explicit SceneGeometry(const scene::Scene& scene) {
        meshes_.reserve(scene.meshes.size());
        for (const auto& mesh : scene.meshes) {
            meshes_.emplace_back(mesh);
            add_instance(Kind::mesh, std::uint32_t(meshes_.size() - 1), mesh.material, mesh.transform,
                         meshes_.back().bounds(), mesh.textures);
        }
        for (const auto& instance : scene.mesh_instances)
            add_instance(Kind::mesh, std::uint32_t(instance.base_mesh), instance.material, instance.transform,
                         meshes_[instance.base_mesh].bounds(), instance.textures);
        for (const auto& sphere : scene.spheres) {
            spheres_.push_back({Vec3<Real>(sphere.center), Real(sphere.radius)});
            add_instance(Kind::sphere, std::uint32_t(spheres_.size() - 1), sphere.material, sphere.transform,
                         spheres_.back().bounds(), sphere.textures);
        }
        // Planes are unbounded, so they stay outside the top-level index and are tested always.
        for (const auto& plane : scene.planes) {
            const glm::dvec3 point = glm::dvec3(plane.transform * glm::dvec4(plane.point, 1.0));
            const glm::dvec3 normal =
                glm::normalize(glm::transpose(glm::inverse(glm::dmat3(plane.transform))) * plane.normal);
            planes_.push_back({Vec3<Real>(point), Vec3<Real>(normal)});
            plane_materials_.push_back(std::uint32_t(plane.material));
            plane_textures_.push_back(add_texture_list(plane.textures));
        }
        std::vector<Aabb<Real>> boxes;
        boxes.reserve(instances_.size());
        for (const auto& instance : instances_) boxes.push_back(instance.world_bounds);
        top_ = Index::build(boxes);
    }

    std::size_t instance_count() const { return instances_.size(); }
    std::size_t triangle_count() const {
        std::size_t total = 0;
        for (const auto& instance : instances_)
            if (instance.kind == Kind::mesh) total += meshes_[instance.shape].triangle_count();
        return total;
    }
    Aabb<Real> bounds() const { return top_.bounds(); }

    // Closest hit in (ray.t_min, ray.t_max]; on a hit, ray.t_max becomes the hit distance.
    template <bool CullBackfaces = false>
    bool intersect(Ray<Real>& ray, Hit<Real>& hit) const {
        bool found = false;
        const auto& order = top_.primitive_indices();
        top_.traverse_closest(ray, ray.t_max, [&](std::uint32_t first, std::uint32_t count, Real& t_max) {
            bool leaf_hit = false;
            for (std::uint32_t i = first; i < first + count; ++i) {
                const std::uint32_t object = order[i];
                if (intersect_instance<CullBackfaces>(instances_[object], ray, t_max, hit)) {
                    hit.object = object;
                    leaf_hit = true;
                }
            }
            found |= leaf_hit;
            return leaf_hit;
        });
        for (std::size_t p = 0; p < planes_.size(); ++p) {
            Real t;
            if (planes_[p].intersect(ray, ray.t_min, ray.t_max, t)) {
                if constexpr (CullBackfaces) {
                    if (glm::dot(ray.direction, planes_[p].normal) > 0) continue;
                }
                ray.t_max = t;
                hit = Hit<Real>{t, std::uint32_t(instances_.size() + p), 0, 0, 0};
                found = true;
            }
        }
        return found;
    }

    // Whether anything lies in (ray.t_min, ray.t_max).
    bool occluded(const Ray<Real>& ray) const {
        const auto& order = top_.primitive_indices();
        const bool blocked =
            top_.traverse_any(ray, ray.t_max, [&](std::uint32_t first, std::uint32_t count, Real& t_max) {
                for (std::uint32_t i = first; i < first + count; ++i)
                    if (occludes(instances_[order[i]], ray, t_max)) return true;
                return false;
            });
        if (blocked) return true;
        for (const auto& plane : planes_) {
            Real t;
            if (plane.intersect(ray, ray.t_min, ray.t_max, t) && t < ray.t_max) return true;
        }
        return false;
    }

    SurfacePoint<Real> surface(const Ray<Real>& ray, const Hit<Real>& hit) const {
        SurfacePoint<Real> point;
        point.position = ray.at(hit.t);
        if (hit.object >= instances_.size()) {
            const std::size_t p = hit.object - instances_.size();
            point.geometric_normal = point.shading_normal = planes_[p].normal;
            point.local_position = point.position;
            point.material = plane_materials_[p];
            point.textures = texture_lists_[plane_textures_[p]];
            return point;
        }
        const Instance& instance = instances_[hit.object];
        point.material = instance.material;
        point.textures = texture_lists_[instance.textures];
        point.local_position = instance.transformed ? instance.to_object(point.position) : point.position;
        Vec3<Real> geometric_normal, shading_normal;
        if (instance.kind == Kind::mesh) {
            meshes_[instance.shape].surface(hit, geometric_normal, shading_normal, point.uv, point.dpdu, point.dpdv);
        } else {
            const SphereShape<Real>& sphere = spheres_[instance.shape];
            geometric_normal = shading_normal = glm::normalize(point.local_position - sphere.center);
            sphere.parametrise(point.local_position, point.uv, point.dpdu, point.dpdv);
        }
        if (instance.transformed) {
            geometric_normal = glm::normalize(instance.normal_to_world * geometric_normal);
            shading_normal = glm::normalize(instance.normal_to_world * shading_normal);
            // Tangents are directions on the surface: they map by the linear part itself.
            point.dpdu = instance.object_to_world_linear * point.dpdu;
            point.dpdv = instance.object_to_world_linear * point.dpdv;
        }
        point.geometric_normal = geometric_normal;
        point.shading_normal = shading_normal;
        return point;
    }

private:
    enum class Kind : std::uint8_t { mesh, sphere };

    struct Instance {
        Kind kind = Kind::mesh;
        bool transformed = false;
        std::uint32_t shape = 0;
        std::uint32_t material = 0;
        Mat4<Real> world_to_object{1};
        Mat3<Real> world_to_object_linear{1};
        Mat3<Real> normal_to_world{1};
        Mat3<Real> object_to_world_linear{1};
        std::uint32_t textures = 0;  // index into texture_lists_
        Aabb<Real> world_bounds;

        Vec3<Real> to_object(const Vec3<Real>& p) const { return Vec3<Real>(world_to_object * Vec4<Real>(p, 1)); }
        // The direction is transformed but not renormalised, so t means the same in both spaces.
        Ray<Real> to_object(const Ray<Real>& ray) const {
            return {to_object(ray.origin), world_to_object_linear * ray.direction, ray.t_min, ray.t_max};
        }
    };

    void add_instance(Kind kind, std::uint32_t shape, std::size_t material, const glm::dmat4& transform,
                      const Aabb<Real>& object_bounds, const std::vector<std::size_t>& textures) {
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
            for (int c = 0; c < 8; ++c)
                instance.world_bounds.extend(
                    Vec3<Real>(transform * glm::dvec4(glm::dvec3(object_bounds.corner(c)), 1.0)));
        } else {
            instance.world_bounds = object_bounds;
        }
        instances_.push_back(instance);
    }

    std::uint32_t add_texture_list(const std::vector<std::size_t>& textures) {
        if (textures.empty()) return 0;
        texture_lists_.emplace_back(textures.begin(), textures.end());
        return std::uint32_t(texture_lists_.size() - 1);
    }

    template <bool CullBackfaces>
    bool intersect_instance(const Instance& instance, const Ray<Real>& ray, Real& t_max, Hit<Real>& hit) const {
        const Ray<Real> local = instance.transformed ? instance.to_object(ray) : ray;
        if (instance.kind == Kind::mesh) return meshes_[instance.shape].template intersect<CullBackfaces>(local, t_max, hit);
        Real t;
        if (!spheres_[instance.shape].intersect(local, ray.t_min, t_max, t)) return false;
        t_max = t;
        hit.t = t;
        hit.primitive = 0;
        return true;
    }

    bool occludes(const Instance& instance, const Ray<Real>& ray, Real t_max) const {
        const Ray<Real> local = instance.transformed ? instance.to_object(ray) : ray;
        if (instance.kind == Kind::mesh) return meshes_[instance.shape].occluded(local, t_max);
        Real t;
        return spheres_[instance.shape].intersect(local, ray.t_min, t_max, t) && t < t_max;
    }

    std::vector<TriangleMesh<Real, Policy>> meshes_;
    std::vector<SphereShape<Real>> spheres_;
    std::vector<PlaneShape<Real>> planes_;
    std::vector<std::uint32_t> plane_materials_;
    std::vector<std::uint32_t> plane_textures_;
    // Each object's texture indices; entry 0 is the empty list that untextured objects share.
    std::vector<std::vector<std::uint32_t>> texture_lists_{1};
    std::vector<Instance> instances_;
    Index top_;
};

}  // namespace prism
