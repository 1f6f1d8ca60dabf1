// A renderer's compile-time configuration: scalar type, acceleration policy (index and triangle
// intersector) and light types. `Renderer<Config<float, Bvh<Watertight>, Lights<PointLight>>>`
// is a type that contains exactly the code those choices need.
#pragma once

#include <prism/accel/accelerator.hpp>
#include <prism/light/light_set.hpp>
#include <prism/light/point_light.hpp>

namespace prism {

template <Scalar RealT, class AccelerationT = Bvh<Watertight>, class LightTypesT = Lights<PointLight>>
    requires AccelerationPolicy<AccelerationT, RealT>
struct Config {
    using Real = RealT;
    using Acceleration = AccelerationT;
    using LightTypes = LightTypesT;
};

}  // namespace prism
