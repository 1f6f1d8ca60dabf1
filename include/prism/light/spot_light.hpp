// The course's spot light: a point light (inverse-square falloff) limited to a cone. With the
// file's FULL apex angles, alpha the angle between the spot axis and the direction to the point:
//   alpha <= falloff / 2                   1
//   falloff / 2 < alpha < coverage / 2     ((cos alpha - cos(coverage / 2)) / (cos(falloff / 2) - cos(coverage / 2)))^4
//   alpha >= coverage / 2                  0
// The factor is 1 at both sides of the falloff edge and 0 at both sides of the coverage edge, so
// the lit disc has no ring at either.
#pragma once

#include <prism/light/light_sample.hpp>

#include <glm/glm.hpp>

#include <cmath>

namespace prism {

template <Scalar Real>
struct SpotLight {
    Vec3<Real> position{0};
    Vec3<Real> axis{0, -1, 0};  // unit, the way the light shines
    Vec3<Real> intensity{0};
    Real cos_half_coverage = 1;
    Real cos_half_falloff = 1;

    static constexpr scene::LightKind kind = scene::LightKind::spot;

    static SpotLight from_description(const scene::SpotLight& light) {
        // Cosines in double: for the course's narrow cones (coverage 10, falloff 8 degrees) they
        // differ only in the third decimal, and their difference is the formula's denominator.
        const double half_coverage = glm::radians(light.coverage_angle) / 2.0;
        const double half_falloff = glm::radians(light.falloff_angle) / 2.0;
        return {Vec3<Real>(light.position), Vec3<Real>(glm::normalize(light.direction)), Vec3<Real>(light.intensity),
                Real(std::cos(half_coverage)), Real(std::cos(half_falloff))};
    }

    static std::vector<SpotLight> from_scene(const scene::Scene& scene) {
        std::vector<SpotLight> lights;
        for (const auto& light : scene.spot_lights) lights.push_back(from_description(light));
        return lights;
    }

    // The cone factor for a direction at angle alpha from the axis, given cos(alpha).
    Real falloff(Real cos_alpha) const {
        if (cos_alpha >= cos_half_falloff) return 1;
        if (cos_alpha <= cos_half_coverage) return 0;
        const Real s = (cos_alpha - cos_half_coverage) / (cos_half_falloff - cos_half_coverage);
        const Real s2 = s * s;
        return s2 * s2;
    }

    LightSample<Real> sample(const ShadingFrame<Real>& at, const Vec2<Real>& = {}) const {
        const Vec3<Real> to_light = position - at.position;
        const Real distance_squared = glm::dot(to_light, to_light);
        const Real distance = std::sqrt(distance_squared);
        const Vec3<Real> direction = to_light / distance;
        const Real cone = falloff(-glm::dot(direction, axis));
        return {direction, distance, intensity * (cone / distance_squared)};
    }
};

}  // namespace prism
