// A renderer's compile-time configuration: scalar type, acceleration policy (index and triangle
// intersector), light types, the shading features that cost work on every ray, and the
// integrator, and the sampler (sampling/sampler_choice.hpp: one fixed pattern, DefaultPattern
// unless named, or ChosenPattern, chosen at run time as the shipped renderers take it).
// `Renderer<Config<float, Bvh<Watertight>, Lights<PointLight>>>` is a type that contains exactly
// the code those choices need: without `Features::textures` no hit looks up a texture, without
// `Features::motion_blur` no ray is moved in time. `covers(needs)` states
// which scenes a Config can render (scene/needs.hpp), so a dispatcher picks among shipped
// Configs without knowing their parts.
#pragma once

#include <prism/accel/accelerator.hpp>
#include <prism/light/light_set.hpp>
#include <prism/light/point_light.hpp>
#include <prism/render/integrator.hpp>
#include <prism/render/whitted_integrator.hpp>
#include <prism/sampling/sampler_choice.hpp>
#include <prism/scene/needs.hpp>

namespace prism {

// Per-ray features a scene may need. Multisampling, depth of field and roughness are not listed:
// they cost nothing on a scene that does not use them (one sample, zero aperture, zero
// roughness take the same branch every time).
struct Features {
    bool textures = false;
    bool motion_blur = false;
};

template <Scalar RealT, class AccelerationT = Bvh<Watertight>, class LightTypesT = Lights<PointLight>,
          Features FeaturesV = Features{}, class IntegratorT = Whitted, class SamplerT = DefaultPattern>
    requires AccelerationPolicy<AccelerationT, RealT> && IntegratorPolicy<IntegratorT> && SamplerPattern<SamplerT, RealT>
struct Config {
    using Real = RealT;
    using Acceleration = AccelerationT;
    using LightTypes = LightTypesT;
    using IntegratorPolicy = IntegratorT;
    using SamplerPolicy = SamplerT;
    static constexpr Features features = FeaturesV;

    // What this configuration renders, stated as the needs it meets: every light kind of its set
    // and each per-ray feature it was compiled with. Precision is not a need but a choice
    // (render_scene).
    static constexpr scene::Needs meets{LightTypes::kinds, features.textures, features.motion_blur};

    static constexpr bool covers(const scene::Needs& needs) {
        return needs.within(meets) && IntegratorT::covers(needs);
    }
};

}  // namespace prism
