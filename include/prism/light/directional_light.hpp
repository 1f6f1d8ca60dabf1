// The course's directional light: parallel light from infinitely far away. Its Radiance arrives
// undiminished (no distance falloff), and a shadow ray towards it reaches to infinity.
#pragma once

#include <prism/light/light_sample.hpp>

#include <glm/glm.hpp>

namespace prism {

template <Scalar Real>
struct DirectionalLight {
    Vec3<Real> to_light{0, 1, 0};  // unit: the opposite of the file's Direction, the way light travels
    Vec3<Real> radiance{0};

    static constexpr scene::LightKind kind = scene::LightKind::directional;

    static std::vector<DirectionalLight> from_scene(const scene::Scene& scene) {
        std::vector<DirectionalLight> lights;
        for (const auto& light : scene.directional_lights)
            lights.push_back({Vec3<Real>(-glm::normalize(light.direction)), Vec3<Real>(light.radiance)});
        return lights;
    }

    LightSample<Real> sample(const ShadingFrame<Real>&, const Vec2<Real>& = {}) const { return {to_light, infinity<Real>, radiance}; }
};

}  // namespace prism
