// All the geometry of a scene in the renderer's precision, as the integrators see it: what finds
// the hits (SceneIndex: the meshes' indices, spheres, planes and the top level, queried through
// the seam of geometry/ray_batch.hpp) and what a hit means (SceneSurfaces: surface points,
// materials, textures, emission, and rays leaving by their error bounds). The two are built once
// each; an index from outside (Embree, accel/embree.hpp) pairs with the same surfaces instead.
#pragma once

#include <prism/accel/accelerator.hpp>
#include <prism/geometry/scene_index.hpp>
#include <prism/geometry/scene_surfaces.hpp>
#include <prism/scene/scene.hpp>

#include <cstdint>
#include <span>

namespace prism {

template <Scalar Real, class Policy, bool MotionBlur = false>
    requires AccelerationPolicy<Policy, Real>
class SceneGeometry : public SceneIndex<Real, Policy, MotionBlur>,
                      public SceneSurfaces<Real, typename Policy::Intersector, MotionBlur> {
public:
    // The surfaces keep each mesh's triangles in the order the index's hits name them.
    explicit SceneGeometry(const scene::Scene& scene)
        : SceneIndex<Real, Policy, MotionBlur>(scene),
          SceneSurfaces<Real, typename Policy::Intersector, MotionBlur>(
              scene, this->placements(), [this](std::size_t m) { return this->slot_order(m); }) {}
};

// The geometry a renderer builds for an acceleration policy: a SceneGeometry traversed by the
// policy's own indices, unless the policy brings its own Geometry (Embree, accel/embree.hpp).
template <class Policy, Scalar Real, bool MotionBlur>
struct GeometryOf {
    using type = SceneGeometry<Real, Policy, MotionBlur>;
};
template <class Policy, Scalar Real, bool MotionBlur>
    requires requires { typename Policy::template Geometry<Real, MotionBlur>; }
struct GeometryOf<Policy, Real, MotionBlur> {
    using type = typename Policy::template Geometry<Real, MotionBlur>;
};

}  // namespace prism
