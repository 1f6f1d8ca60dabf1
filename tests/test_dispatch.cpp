// The dispatcher's shape: a scene's needs measured once (scene/needs.hpp), each Config's
// statement of what it covers, and render_scene taking the first shipped Config that covers the
// scene.
#include <prism/render/render_scene.hpp>

#include <doctest/doctest.h>

#include <sstream>

namespace scene = prism::scene;

namespace {

scene::Scene point_lit() {
    scene::Scene world;
    world.point_lights.push_back({"1", {0, 5, 0}, {10, 10, 10}});
    return world;
}

}  // namespace

TEST_CASE("Needs: light kinds, textures and motion blur, measured from the description") {
    scene::Scene world = point_lit();
    scene::Needs needs = scene::measure_needs(world);
    CHECK(needs.lights == scene::bit(scene::LightKind::point));
    CHECK_FALSE(needs.textures);
    CHECK_FALSE(needs.motion_blur);
    world.spot_lights.push_back({});
    world.environment_lights.push_back({});
    world.spheres.push_back({"ball", 0, {0, 0, 0}, 1, glm::dmat4(1.0)});
    world.spheres.back().motion = {0, 1, 0};
    needs = scene::measure_needs(world);
    CHECK(needs.lights == (scene::bit(scene::LightKind::point) | scene::bit(scene::LightKind::spot) |
                           scene::bit(scene::LightKind::environment)));
    CHECK(needs.motion_blur);
    const scene::Needs point_only{scene::bit(scene::LightKind::point)};
    CHECK_FALSE(needs.within(point_only));
    CHECK(needs.beyond(point_only) == "spot lights, environment lights, motion blur (MotionBlur)");
    CHECK(point_only.within(needs));
    CHECK(point_only.beyond(needs).empty());
}

TEST_CASE_TEMPLATE("Config::covers: every light kind of its set and each compiled feature", Real, float, double) {
    using Fitted = prism::Config<Real, prism::Bvh<prism::Watertight>, prism::PointLightSet, prism::no_features>;
    using Complete = prism::Config<Real, prism::Bvh<prism::Watertight>, prism::AllLightSet, prism::all_features>;
    scene::Needs needs{scene::bit(scene::LightKind::point)};
    CHECK(Fitted::covers(needs));
    CHECK(Complete::covers(needs));
    needs.textures = true;
    CHECK_FALSE(Fitted::covers(needs));
    CHECK(Complete::covers(needs));
    needs = {scene::bit(scene::LightKind::area)};
    CHECK_FALSE(Fitted::covers(needs));
    CHECK(Complete::covers(needs));
    // A set covers exactly the union of its types' kinds.
    using PointAndSpot = prism::Lights<prism::PointLight, prism::SpotLight>;
    CHECK(PointAndSpot::kinds == (scene::bit(scene::LightKind::point) | scene::bit(scene::LightKind::spot)));
    static_assert(prism::Integrator<typename prism::Renderer<Fitted>::Integrator, Real>);
}

TEST_CASE("render_scene: the first shipped Config that covers the scene renders it, and the log says which") {
    scene::Scene world = point_lit();
    world.cameras.push_back({});
    scene::Camera& camera = world.cameras.back();
    camera.width = camera.height = 2;
    camera.position = {0, 0, 5};
    world.materials.push_back({});
    world.spheres.push_back({"ball", 0, {0, 0, 0}, 1, glm::dmat4(1.0)});
    std::ostringstream log;
    CHECK(prism::render_scene(world, {}, log).size() == 1);
    CHECK(log.str().find("point lights only") != std::string::npos);
    world.directional_lights.push_back({"sun", {0, -1, 0}, {1, 1, 1}});
    log.str("");
    CHECK(prism::render_scene(world, {}, log).size() == 1);
    CHECK(log.str().find("the scene has directional lights") != std::string::npos);
}
