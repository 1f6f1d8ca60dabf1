// The course's area light: a parallelogram of constant radiance, sampled at one uniform point per
// shading point and camera sample. With the point q chosen with density 1/A, the irradiance
// estimate is L A |cos theta_l| / d^2 (theta_l between the light's normal and the direction to
// the shading point): the light shines from both faces, as the course defines it, so a light
// placed in a ceiling lights the room whichever way its normal was written.
#pragma once

#include <prism/light/light_sample.hpp>

#include <cmath>

namespace prism {

template <Scalar Real>
struct AreaLight {
    Vec3<Real> corner{0};
    Vec3<Real> edge1{1, 0, 0};
    Vec3<Real> edge2{0, 0, 1};
    Vec3<Real> normal{0, 1, 0};  // unit
    Real area = 1;
    Vec3<Real> radiance{0};

    static constexpr scene::LightKind kind = scene::LightKind::area;

    static std::vector<AreaLight> from_scene(const scene::Scene& scene) {
        std::vector<AreaLight> lights;
        for (const auto& light : scene.area_lights) {
            const glm::dvec3 cross = glm::cross(light.edge1, light.edge2);
            const double area = glm::length(cross);
            lights.push_back({Vec3<Real>(light.corner), Vec3<Real>(light.edge1), Vec3<Real>(light.edge2),
                              Vec3<Real>(area > 0 ? cross / area : glm::dvec3(0, 1, 0)), Real(area),
                              Vec3<Real>(light.radiance)});
        }
        return lights;
    }

    LightSample<Real> sample(const ShadingFrame<Real>& at, const Vec2<Real>& u) const {
        const Vec3<Real> point = corner + u.x * edge1 + u.y * edge2;
        const Vec3<Real> to_light = point - at.position;
        const Real distance_squared = glm::dot(to_light, to_light);
        const Real distance = std::sqrt(distance_squared);
        if (!(distance > 0)) return {Vec3<Real>(0, 0, 1), Real(0), Vec3<Real>(0)};
        const Vec3<Real> direction = to_light / distance;
        const Real cos_light = std::abs(glm::dot(normal, direction));
        return {direction, distance, radiance * (area * cos_light / distance_squared)};
    }
};

}  // namespace prism
