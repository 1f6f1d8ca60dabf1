// The course's <LightMesh>: a triangle mesh whose surface emits a constant Radiance from both
// faces. Direct lighting samples it by area: a triangle chosen with probability proportional to
// its area, then a uniform point of it (Pharr, Jakob and Humphreys, "Physically Based Rendering",
// 4th ed., sec. 6.5.4), so a point q has density 1 / A over the whole mesh and the solid-angle
// density at x is |x - q|^2 / (A |cos theta_q|) (pbrt sec. 4.2.3's change of measure).
// Instances of a LightMesh emit too; each mesh and instance is one light, in world space.
#pragma once

#include <prism/light/light_sample.hpp>
#include <prism/sampling/piecewise_constant.hpp>
#include <prism/scene/scene.hpp>

#include <cmath>
#include <cstdint>
#include <limits>

namespace prism {

// The number each object has (Hit::object): the meshes in order, then the mesh instances,
// then the spheres (place_objects, geometry/placement.hpp, numbers them in this order).
inline std::uint32_t scene_object_of_mesh(const scene::Scene&, std::size_t mesh) { return std::uint32_t(mesh); }
inline std::uint32_t scene_object_of_instance(const scene::Scene& scene, std::size_t instance) {
    return std::uint32_t(scene.meshes.size() + instance);
}
inline std::uint32_t scene_object_of_sphere(const scene::Scene& scene, std::size_t sphere) {
    return std::uint32_t(scene.meshes.size() + scene.mesh_instances.size() + sphere);
}

template <Scalar Real>
struct LightMesh {
    struct Triangle {
        Vec3<Real> a{0}, edge1{0}, edge2{0};
        Vec3<Real> normal{0, 0, 1};  // unit
    };
    std::vector<Triangle> triangles;  // world space
    PiecewiseConstant1D<Real> by_area;
    Real area = 0;
    Vec3<Real> radiance{0};
    std::uint32_t object = 0;  // SceneGeometry's index of the mesh or instance

    static constexpr scene::LightKind kind = scene::LightKind::object;

    // World-space triangles are computed in double from the file's values and rounded once.
    static LightMesh make(const scene::Mesh& mesh, const glm::dmat4& transform, std::uint32_t object) {
        LightMesh light;
        light.radiance = Vec3<Real>(mesh.radiance);
        light.object = object;
        std::vector<Real> areas;
        double total = 0;
        for (const auto& triangle : mesh.triangles) {
            const auto world = [&](std::uint32_t v) { return glm::dvec3(transform * glm::dvec4(mesh.positions[v], 1.0)); };
            const glm::dvec3 a = world(triangle[0]), b = world(triangle[1]), c = world(triangle[2]);
            const glm::dvec3 cross = glm::cross(b - a, c - a);
            const double length = glm::length(cross);
            light.triangles.push_back({Vec3<Real>(a), Vec3<Real>(b - a), Vec3<Real>(c - a),
                                       Vec3<Real>(length > 0 ? cross / length : glm::dvec3(0, 0, 1))});
            areas.push_back(Real(length / 2));
            total += length / 2;
        }
        light.by_area = PiecewiseConstant1D<Real>(std::move(areas));
        light.area = Real(total);
        return light;
    }

    static std::vector<LightMesh> from_scene(const scene::Scene& scene) {
        std::vector<LightMesh> lights;
        for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
            const scene::Mesh& mesh = scene.meshes[m];
            if (mesh.radiance != glm::dvec3(0.0)) lights.push_back(make(mesh, mesh.transform, scene_object_of_mesh(scene, m)));
        }
        for (std::size_t i = 0; i < scene.mesh_instances.size(); ++i) {
            const scene::MeshInstance& instance = scene.mesh_instances[i];
            const scene::Mesh& mesh = scene.meshes[instance.base_mesh];
            if (mesh.radiance != glm::dvec3(0.0))
                lights.push_back(make(mesh, instance.transform, scene_object_of_instance(scene, i)));
        }
        std::erase_if(lights, [](const LightMesh& light) { return !(light.area > 0); });
        return lights;
    }

    // The solid-angle density of reaching `point` (with unit normal `normal`) on this mesh from
    // `from` by sample(): |from - point|^2 / (A |cos|).
    Real pdf(const Vec3<Real>& from, const Vec3<Real>& point, const Vec3<Real>& normal) const {
        const Vec3<Real> to_light = point - from;
        const Real distance_squared = glm::dot(to_light, to_light);
        const Real cos_light = std::abs(glm::dot(normal, to_light)) / std::sqrt(distance_squared);
        if (!(cos_light > 0)) return 0;
        return distance_squared / (area * cos_light);
    }

    LightSample<Real> sample(const ShadingFrame<Real>& at, const Vec2<Real>& u) const {
        const auto chosen = by_area.sample(u.x);
        // The position of u.x within the chosen cell is again uniform: it places the point.
        const Real reused = std::min(chosen.x * Real(by_area.size()) - Real(chosen.cell), Real(1) - std::numeric_limits<Real>::epsilon());
        const Triangle& triangle = triangles[chosen.cell];
        const Real root = std::sqrt(std::max(reused, Real(0)));
        const Vec3<Real> point = triangle.a + root * (1 - u.y) * triangle.edge1 + root * u.y * triangle.edge2;
        const Vec3<Real> to_light = point - at.position;
        const Real distance_squared = glm::dot(to_light, to_light);
        const Real distance = std::sqrt(distance_squared);
        if (!(distance > 0)) return {Vec3<Real>(0, 0, 1), Real(0), Vec3<Real>(0), Real(0)};
        const Vec3<Real> direction = to_light / distance;
        const Real cos_light = std::abs(glm::dot(triangle.normal, direction));
        if (!(cos_light > 0)) return {direction, distance, Vec3<Real>(0), Real(0)};
        const Real density = distance_squared / (area * cos_light);
        return {direction, distance, radiance / density, density};
    }
};

}  // namespace prism
