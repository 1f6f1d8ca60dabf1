// The course's point light: Intensity falls off with the inverse square of the distance.
#pragma once

#include <prism/light/light_sample.hpp>

#include <cmath>

namespace prism {

template <Scalar Real>
struct PointLight {
    Vec3<Real> position{0};
    Vec3<Real> intensity{0};

    static constexpr scene::LightKind kind = scene::LightKind::point;

    static std::vector<PointLight> from_scene(const scene::Scene& scene) {
        std::vector<PointLight> lights;
        for (const auto& light : scene.point_lights) lights.push_back({Vec3<Real>(light.position), Vec3<Real>(light.intensity)});
        return lights;
    }

    LightSample<Real> sample(const ShadingFrame<Real>& at, const Vec2<Real>& = {}) const {
        const Vec3<Real> to_light = position - at.position;
        const Real distance_squared = glm::dot(to_light, to_light);
        const Real distance = std::sqrt(distance_squared);
        return {to_light / distance, distance, intensity / distance_squared};
    }
};

}  // namespace prism
