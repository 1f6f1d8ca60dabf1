// The renderer a Config composes: geometry built in the Config's precision with its
// acceleration policy, its light set, the course's integrator, and tiles of pixels rendered in
// parallel with TBB into an HDR image.
#pragma once

#include <prism/camera/pinhole_camera.hpp>
#include <prism/geometry/scene_geometry.hpp>
#include <prism/image/image.hpp>
#include <prism/render/config.hpp>
#include <prism/render/whitted_integrator.hpp>

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace prism {

template <class C>
class Renderer {
public:
    using Real = typename C::Real;
    using Geometry = SceneGeometry<Real, typename C::Acceleration>;
    using LightSetT = typename C::LightTypes::template Set<Real>;

    static constexpr int tile_size = 16;

    explicit Renderer(const scene::Scene& scene, bool cull_backfaces = false)
        : geometry_(scene), lights_(scene), materials_(convert_materials(scene)),
          integrator_(geometry_, lights_, materials_, Vec3<Real>(scene.ambient_light), Vec3<Real>(scene.background_color),
                      IntegratorSettings{scene.max_recursion_depth, scene.shadow_ray_epsilon, cull_backfaces}) {}

    // A renderer holds references into itself (the integrator into geometry and lights).
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    const Geometry& geometry() const { return geometry_; }
    const LightSetT& lights() const { return lights_; }

    // Renders `camera` at width x height (0: the camera's own resolution). `on_tile(pixels)` is
    // called from worker threads after each finished tile, for progress reporting.
    template <class OnTile = void (*)(int)>
    Image render(const scene::Camera& camera, int width = 0, int height = 0, OnTile on_tile = [](int) {}) const {
        if (width <= 0) width = camera.width;
        if (height <= 0) height = camera.height;
        const PinholeCamera<Real> pinhole(camera, width, height);
        Image image(width, height);
        tbb::parallel_for(tbb::blocked_range2d<int>(0, height, tile_size, 0, width, tile_size),
                          [&](const tbb::blocked_range2d<int>& tile) {
                              for (int y = tile.rows().begin(); y < tile.rows().end(); ++y)
                                  for (int x = tile.cols().begin(); x < tile.cols().end(); ++x)
                                      image(x, y) = glm::vec3(integrator_.radiance(
                                          pinhole.ray(Real(x) + Real(0.5), Real(y) + Real(0.5)), 0));
                              on_tile(int(tile.rows().size() * tile.cols().size()));
                          });
        return image;
    }

    // Radiance along one ray (unit direction), for tests and tools.
    Vec3<Real> radiance(const Ray<Real>& ray) const { return integrator_.radiance(ray, 0); }

private:
    static std::vector<Material<Real>> convert_materials(const scene::Scene& scene) {
        std::vector<Material<Real>> materials;
        for (const auto& material : scene.materials) materials.emplace_back(material);
        return materials;
    }

    Geometry geometry_;
    LightSetT lights_;
    std::vector<Material<Real>> materials_;
    WhittedIntegrator<Real, Geometry, LightSetT> integrator_;
};

}  // namespace prism
