// What a scene needs from a renderer, measured once from the plain description: its light kinds
// and its per-ray features (textures, motion blur). (The precision it needs is measured apart,
// scene/features.hpp, because it is a choice among equally able renderers, not a need.) "Model no more than a scene needs": the
// dispatcher (render/render_scene.hpp) renders with the first shipped Config that covers these
// needs, and says why. A light kind, feature or integrator added to the scene description is
// added here, once; each Config states what it covers (render/config.hpp).
#pragma once

#include <prism/scene/scene.hpp>

#include <algorithm>
#include <cstdint>
#include <string>

namespace prism::scene {

// One bit per light type of the scene description; each prism light type names its kind, and a
// light set covers the union of its types' kinds.
// `object`: LightMesh and LightSphere, geometry that emits.
enum class LightKind : std::uint32_t { point, directional, spot, area, environment, object, count };

using LightKinds = std::uint32_t;  // a set of LightKind bits

constexpr LightKinds bit(LightKind kind) { return LightKinds(1) << std::uint32_t(kind); }

inline const char* name(LightKind kind) {
    switch (kind) {
        case LightKind::point: return "point lights";
        case LightKind::directional: return "directional lights";
        case LightKind::spot: return "spot lights";
        case LightKind::area: return "area lights";
        case LightKind::environment: return "environment lights";
        case LightKind::object: return "object lights (LightMesh, LightSphere)";
        case LightKind::count: break;
    }
    return "?";
}

struct Needs {
    LightKinds lights = 0;
    bool textures = false;
    bool motion_blur = false;
    // Some camera asks for <Renderer>PathTracing</Renderer>: an integrator policy states
    // whether it covers this (render/integrator.hpp); light sets and features do not.
    bool path_tracing = false;

    // Whether `covered` (what a renderer can do, stated as needs) includes all of these.
    constexpr bool within(const Needs& covered) const {
        return (lights & ~covered.lights) == 0 && (covered.textures || !textures) &&
               (covered.motion_blur || !motion_blur);
    }

    // What these needs ask beyond `covered`, for messages; empty when within it.
    std::string beyond(const Needs& covered) const {
        std::string reason;
        const auto add = [&](bool needed, const char* what) {
            if (!needed) return;
            reason += reason.empty() ? "" : ", ";
            reason += what;
        };
        for (std::uint32_t k = 0; k < std::uint32_t(LightKind::count); ++k)
            add((lights & ~covered.lights & bit(LightKind(k))) != 0, name(LightKind(k)));
        add(textures && !covered.textures, "textures");
        add(motion_blur && !covered.motion_blur, "motion blur (MotionBlur)");
        return reason;
    }
};

// The light kinds a scene uses: the one place that maps the description's light lists to kinds.
inline LightKinds light_kinds(const Scene& scene) {
    LightKinds kinds = 0;
    const auto add = [&](bool present, LightKind kind) { kinds |= present ? bit(kind) : 0; };
    add(!scene.point_lights.empty(), LightKind::point);
    add(!scene.directional_lights.empty(), LightKind::directional);
    add(!scene.spot_lights.empty(), LightKind::spot);
    add(!scene.area_lights.empty(), LightKind::area);
    add(!scene.environment_lights.empty(), LightKind::environment);
    const auto emits = [](const auto& objects) {
        return std::any_of(objects.begin(), objects.end(),
                           [](const auto& object) { return object.radiance != glm::dvec3(0.0); });
    };
    add(emits(scene.meshes) || emits(scene.spheres), LightKind::object);
    return kinds;
}

inline bool has_moving_objects(const Scene& scene) {
    const auto moving = [](const auto& objects) {
        return std::any_of(objects.begin(), objects.end(),
                           [](const auto& object) { return object.motion != glm::dvec3(0.0); });
    };
    return moving(scene.meshes) || moving(scene.spheres) || moving(scene.mesh_instances);
}

inline bool has_path_traced_camera(const Scene& scene) {
    return std::any_of(scene.cameras.begin(), scene.cameras.end(),
                       [](const Camera& camera) { return camera.renderer.path_tracing; });
}

inline Needs measure_needs(const Scene& scene) {
    Needs needs;
    needs.lights = light_kinds(scene);
    needs.textures = !scene.textures.empty();
    needs.motion_blur = has_moving_objects(scene);
    needs.path_tracing = has_path_traced_camera(scene);
    return needs;
}

}  // namespace prism::scene
