// The course's <LightSphere>: a sphere whose surface emits a constant Radiance. Direct lighting
// samples the cone the sphere subtends from the shading point, uniformly in solid angle (Shirley
// and Wang 1994; Pharr, Jakob and Humphreys, "Physically Based Rendering", 4th ed., sec. 6.2.4),
// so small and distant spheres converge as fast as large ones: every sample hits the sphere.
// A transformed sphere (an ellipsoid under a non-uniform Scaling, as
// cornellbox_jaroslav_glossy_area_ellipsoid has) is sampled by the cone in its object space;
// the point found is carried to world space and its density converted by the area scale of the
// transformation at that point, |det M| |M^-T n|, so the estimate stays exact for any affine map.
#pragma once

#include <prism/light/light_mesh.hpp>
#include <prism/light/light_sample.hpp>
#include <prism/sampling/hemisphere.hpp>

#include <algorithm>
#include <cmath>

namespace prism {

template <Scalar Real>
struct LightSphere {
    Vec3<Real> center{0};  // object space
    Real radius = 1;
    Mat4<Real> to_world{1}, to_object{1};
    Mat3<Real> normal_to_world{1};  // M^-T
    Real determinant = 1;           // |det M|
    Vec3<Real> radiance{0};
    std::uint32_t object = 0;  // its object number (place_objects)

    static constexpr scene::LightKind kind = scene::LightKind::object;

    static LightSphere make(const glm::dvec3& center, double radius, const glm::dmat4& transform,
                            const glm::dvec3& radiance, std::uint32_t object) {
        const glm::dmat4 inverse = glm::inverse(transform);
        return {Vec3<Real>(center),
                Real(radius),
                Mat4<Real>(transform),
                Mat4<Real>(inverse),
                Mat3<Real>(glm::transpose(glm::dmat3(inverse))),
                Real(std::abs(glm::determinant(glm::dmat3(transform)))),
                Vec3<Real>(radiance),
                object};
    }

    static std::vector<LightSphere> from_scene(const scene::Scene& scene) {
        std::vector<LightSphere> lights;
        for (std::size_t s = 0; s < scene.spheres.size(); ++s) {
            const scene::Sphere& sphere = scene.spheres[s];
            if (sphere.radiance != glm::dvec3(0.0))
                lights.push_back(make(sphere.center, sphere.radius, sphere.transform, sphere.radiance,
                                      scene_object_of_sphere(scene, s)));
        }
        return lights;
    }

    // 1 - cos(theta_max) of the cone a sphere of radius r subtends at distance d; for narrow
    // cones from sin^2 / 2 (+ sin^4 / 8), since 1 - sqrt(1 - s) loses every digit in float below
    // s ~ 1e-7 (pbrt-v4 uses the same switch at sin^2 < 0.00068523, 1.5 degrees).
    static Real cone_width(Real distance_squared, Real radius) {
        const Real sin2 = radius * radius / distance_squared;
        if (sin2 < Real(0.00068523)) return sin2 / 2 + sin2 * sin2 / 8;
        return 1 - std::sqrt(std::max(Real(0), 1 - sin2));
    }

    // The world-space density of `point` on the surface, per unit area, for a point reached
    // with object-space solid-angle density `cone_density` from `from_object`.
    Real area_density(const Vec3<Real>& from_object, const Vec3<Real>& point_object, Real cone_density) const {
        const Vec3<Real> offset = point_object - from_object;
        const Real distance_squared = glm::dot(offset, offset);
        const Vec3<Real> normal = (point_object - center) / radius;
        const Real cos_object = std::abs(glm::dot(normal, offset)) / std::sqrt(distance_squared);
        const Real area_scale = determinant * glm::length(normal_to_world * normal);
        return cone_density * cos_object / distance_squared / area_scale;
    }

    // The solid-angle density of reaching `point` (on this sphere, unit world normal `normal`)
    // from `from` by sample(); zero from inside the sphere, which sample() does not light.
    Real pdf(const Vec3<Real>& from, const Vec3<Real>& point, const Vec3<Real>& normal) const {
        const Vec3<Real> from_object = Vec3<Real>(to_object * Vec4<Real>(from, 1));
        const Vec3<Real> axis = center - from_object;
        const Real axis_squared = glm::dot(axis, axis);
        if (!(axis_squared > radius * radius)) return 0;
        const Real cone_density = 1 / (2 * pi<Real> * cone_width(axis_squared, radius));
        const Vec3<Real> point_object = Vec3<Real>(to_object * Vec4<Real>(point, 1));
        const Vec3<Real> to_light = point - from;
        const Real distance_squared = glm::dot(to_light, to_light);
        const Real cos_light = std::abs(glm::dot(normal, to_light)) / std::sqrt(distance_squared);
        if (!(cos_light > 0)) return 0;
        return area_density(from_object, point_object, cone_density) * distance_squared / cos_light;
    }

    LightSample<Real> sample(const ShadingFrame<Real>& at, const Vec2<Real>& u) const {
        const Vec3<Real> from_object = Vec3<Real>(to_object * Vec4<Real>(at.position, 1));
        const Vec3<Real> axis = center - from_object;
        const Real axis_squared = glm::dot(axis, axis);
        if (!(axis_squared > radius * radius)) return {Vec3<Real>(0, 0, 1), Real(0), Vec3<Real>(0), Real(0)};
        const Real axis_length = std::sqrt(axis_squared);
        const Vec3<Real> w = axis / axis_length;
        const Real width = cone_width(axis_squared, radius);
        // The point is placed from the sphere's centre by the angle alpha between the sphere's
        // normal there and the axis (pbrt-v4's Sphere::Sample): intersecting the ray instead
        // subtracts nearly equal distances, which in float puts points of a sphere 2000 radii
        // away 10% off its surface.
        const Real sin2_max = radius * radius / axis_squared;
        const Real sin_max = std::sqrt(sin2_max);
        const Real cos_theta = 1 - u.x * width;
        const Real sin2_theta = sin2_max < Real(0.00068523) ? sin2_max * u.x : (2 - u.x * width) * u.x * width;
        const Real cos_alpha = sin2_theta / sin_max + cos_theta * std::sqrt(std::max(Real(0), 1 - sin2_theta / sin2_max));
        const Real sin_alpha = std::sqrt(std::max(Real(0), 1 - cos_alpha * cos_alpha));
        const Real phi = 2 * pi<Real> * u.y;
        const auto [tangent, bitangent] = orthonormal_basis(w);
        const Vec3<Real> outward = -(sin_alpha * std::cos(phi) * tangent + sin_alpha * std::sin(phi) * bitangent + cos_alpha * w);
        const Vec3<Real> point_object = center + radius * outward;
        const Real cone_density = 1 / (2 * pi<Real> * width);

        const Vec3<Real> point = Vec3<Real>(to_world * Vec4<Real>(point_object, 1));
        const Vec3<Real> to_light = point - at.position;
        const Real distance_squared = glm::dot(to_light, to_light);
        const Real distance = std::sqrt(distance_squared);
        if (!(distance > 0)) return {Vec3<Real>(0, 0, 1), Real(0), Vec3<Real>(0), Real(0)};
        const Vec3<Real> direction = to_light / distance;
        const Vec3<Real> normal = unit_vector(normal_to_world * (point_object - center));
        const Real cos_light = std::abs(glm::dot(normal, direction));
        if (!(cos_light > 0)) return {direction, distance, Vec3<Real>(0), Real(0)};
        const Real density = area_density(from_object, point_object, cone_density) * distance_squared / cos_light;
        if (!(density > 0) || !std::isfinite(density)) return {direction, distance, Vec3<Real>(0), Real(0)};
        return {direction, distance, radiance / density, density};
    }
};

}  // namespace prism
