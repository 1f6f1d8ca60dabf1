// A renderer's compile-time configuration: scalar type, acceleration policy (index and triangle
// intersector), light types, and the shading features that cost work on every ray.
// `Renderer<Config<float, Bvh<Watertight>, Lights<PointLight>>>` is a type that contains exactly
// the code those choices need: without `Features::textures` no hit looks up a texture, without
// `Features::motion_blur` no ray is moved in time.
#pragma once

#include <prism/accel/accelerator.hpp>
#include <prism/light/light_set.hpp>
#include <prism/light/point_light.hpp>

namespace prism {

// Per-ray features a scene may need. Multisampling, depth of field and roughness are not listed:
// they cost nothing on a scene that does not use them (one sample, zero aperture, zero
// roughness take the same branch every time).
struct Features {
    bool textures = false;
    bool motion_blur = false;
};

template <Scalar RealT, class AccelerationT = Bvh<Watertight>, class LightTypesT = Lights<PointLight>,
          Features FeaturesV = Features{}>
    requires AccelerationPolicy<AccelerationT, RealT>
struct Config {
    using Real = RealT;
    using Acceleration = AccelerationT;
    using LightTypes = LightTypesT;
    static constexpr Features features = FeaturesV;
};

}  // namespace prism
