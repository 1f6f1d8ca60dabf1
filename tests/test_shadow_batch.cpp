// Shadow rays tested several at a time (SceneGeometry::occluded_each, a point's rays to its
// lights): every ray of the batch, for every set of lanes, gets what occluded gives it alone,
// in scenes of direct spheres (plain, translated, scaled-rotated), planes, one- and two-leaf
// world meshes and transformed top-level meshes, for float and double; on rays through and
// grazing the objects, and on shadow rays to lights from points near the surfaces.
#include <prism/geometry/scene_geometry.hpp>

#include <glm/gtc/matrix_transform.hpp>

#include <doctest/doctest.h>

#include <array>
#include <cstdint>
#include <random>
#include <vector>

namespace {

namespace scene = prism::scene;

glm::dvec3 random_unit(std::mt19937& random) {
    std::uniform_real_distribution<double> uniform(-1, 1);
    glm::dvec3 v;
    do v = {uniform(random), uniform(random), uniform(random)};
    while (glm::dot(v, v) > 1 || glm::dot(v, v) < 1e-6);
    return glm::normalize(v);
}

// Spheres of each kind the direct test tells apart, two planes, and optionally a floor and a
// wall (world-space meshes of one leaf each) and a transformed plate in the top level.
scene::Scene shadow_world(bool with_meshes) {
    scene::Scene world;
    world.materials.push_back({});
    world.spheres.push_back({"plain", 0, {0, 0, 0}, 1.0, glm::dmat4(1.0)});
    world.spheres.push_back({"translated", 0, {0.5, 0, 0}, 0.75, glm::translate(glm::dmat4(1.0), glm::dvec3(2.5, 0.25, -1))});
    glm::dmat4 ellipsoid = glm::translate(glm::dmat4(1.0), glm::dvec3(-2.5, 0.5, 0.5));
    ellipsoid = glm::rotate(ellipsoid, 0.7, glm::normalize(glm::dvec3(1, 2, 3)));
    ellipsoid = glm::scale(ellipsoid, glm::dvec3(1.5, 0.25, 0.8));
    world.spheres.push_back({"ellipsoid", 0, {0, 0.2, 0}, 1.0, ellipsoid});
    world.planes.push_back({"back", 0, {0, 0, -4}, glm::normalize(glm::dvec3(0.1, 0.2, 1)), glm::dmat4(1.0)});
    world.planes.push_back({"side", 0, {5, 0, 0}, glm::normalize(glm::dvec3(-1, 0.1, 0)), glm::dmat4(1.0)});
    if (with_meshes) {
        scene::Mesh floor;
        floor.positions = {{-6, -1.5, -6}, {6, -1.5, -6}, {6, -1.5, 6}, {-6, -1.5, 6}};
        floor.triangles = {{0, 2, 1}, {0, 3, 2}};
        world.meshes.push_back(floor);
        scene::Mesh plate;
        plate.positions = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
        plate.triangles = {{0, 2, 1}, {0, 3, 2}};
        plate.transform = glm::rotate(glm::translate(glm::dmat4(1.0), glm::dvec3(-2, 0.5, 1.5)), 0.9,
                                      glm::normalize(glm::dvec3(1, 0.3, -0.5)));
        world.meshes.push_back(plate);
    }
    return world;
}

}  // namespace

TEST_CASE_TEMPLATE("SceneGeometry: shadow rays tested several at a time get what each gets alone", Real, float, double) {
    using Geometry = prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>>;
    for (const bool with_meshes : {false, true}) {
        CAPTURE(with_meshes);
        const scene::Scene world = shadow_world(with_meshes);
        const Geometry geometry(world);
        REQUIRE(geometry.occlusion_batches());

        std::mt19937 random(11);
        std::uniform_real_distribution<double> uniform(-1, 1), fraction(0, 1);
        const std::array<glm::dvec3, 8> lights = {glm::dvec3(0, 4, 0),   {3, 3, 2},  {-3, 2, -2}, {0.5, 1.2, 0.1},
                                                  {4.5, -1, 3}, {-4, 3.5, 3}, {1, -1.2, -3}, {0, 0, 5}};
        std::size_t blocked = 0, rays = 0;
        for (int batch = 0; batch < 6000; ++batch) {
            std::array<prism::Ray<Real>, 8> shadows;
            std::uint32_t lanes = 0;
            // A point on or near a sphere, the floor or in open space; its rays to the lights.
            glm::dvec3 from;
            if (batch % 3 == 0) {
                const scene::Sphere& sphere = world.spheres[std::size_t(batch / 3) % world.spheres.size()];
                from = glm::dvec3(sphere.transform * glm::dvec4(sphere.center + sphere.radius * random_unit(random), 1.0));
                from += 1e-4 * random_unit(random);
            } else if (batch % 3 == 1) {
                from = {5 * uniform(random), -1.5 + 1e-4 * uniform(random), 5 * uniform(random)};
            } else {
                from = 5.0 * glm::dvec3(uniform(random), uniform(random), uniform(random));
            }
            for (std::size_t i = 0; i < lights.size(); ++i) {
                if (fraction(random) < 0.25) continue;
                const glm::dvec3 to_light = lights[i] - from;
                prism::Ray<Real> ray{prism::Vec3<Real>(from), prism::Vec3<Real>(glm::normalize(to_light)), Real(0),
                                     Real(glm::length(to_light))};
                if (batch % 7 == 0) ray.direction = prism::Vec3<Real>(random_unit(random));  // any direction
                if (batch % 11 == 0) ray.t_min = Real(1e-3);
                shadows[i] = ray;
                lanes |= std::uint32_t(1) << i;
            }
            std::uint32_t expected = 0;
            for (std::uint32_t rest = lanes; rest != 0; rest &= rest - 1) {
                const int lane = std::countr_zero(rest);
                if (geometry.occluded(shadows[std::size_t(lane)])) expected |= std::uint32_t(1) << lane;
                ++rays;
            }
            const std::uint32_t found = geometry.occluded_each(shadows.data(), lanes);
            CHECK(found == expected);
            blocked += std::size_t(std::popcount(expected));
        }
        // Both answers are common: the comparison is not of misses (or of hits) alone.
        CHECK(blocked > rays / 10);
        CHECK(blocked < rays * 9 / 10);
    }
}
