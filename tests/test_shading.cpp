// Shading and viewing, for float and double: the Fresnel reflectances against the published
// values and the exact equations, the pinhole camera's rays through pixel centres, and tiny
// scenes rendered end to end whose centre pixel is computed by hand: Blinn-Phong under one point
// light, a shadow, a mirror and the recursion limit.
#include <prism/camera/pinhole_camera.hpp>
#include <prism/material/fresnel.hpp>
#include <prism/render/config.hpp>
#include <prism/render/renderer.hpp>
#include <prism/render/stored_whole.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <complex>
#include <cstring>
#include <limits>
#include <random>
#include <type_traits>

namespace {

namespace scene = prism::scene;

// Relative tolerance for values computed with a handful of roundings in Real.
template <class Real>
constexpr double tolerance = std::is_same_v<Real, float> ? 1e-5 : 1e-12;

// The Fresnel equations for unpolarised light, written out here from Snell's law so the
// header's version is checked against an independent derivation.
struct Reflectance {
    double s, p;
    double average() const { return (s + p) / 2; }
};
Reflectance dielectric_reflectance(double theta_incident, double n1, double n2) {
    const double cos_i = std::cos(theta_incident);
    const double sin_t = n1 / n2 * std::sin(theta_incident);
    const double cos_t = std::sqrt(1 - sin_t * sin_t);
    const double rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    const double rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    return {rs * rs, rp * rp};
}
double cos_transmitted(double theta_incident, double n1, double n2) {
    const double sin_t = n1 / n2 * std::sin(theta_incident);
    return std::sqrt(1 - sin_t * sin_t);
}
// A conductor's exact reflectance from its complex index n + ik.
double conductor_reflectance_exact(double cos_i, double n, double k) {
    const std::complex<double> eta(n, k);
    const std::complex<double> cos_t = std::sqrt(1.0 - (1 - cos_i * cos_i) / (eta * eta));
    const std::complex<double> rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    const std::complex<double> rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return (std::norm(rs) + std::norm(rp)) / 2;
}

constexpr double quarter_turn = 1.5707963267948966;

}  // namespace

// ---------------------------------------------------------------------------------------------
// Fresnel

TEST_CASE_TEMPLATE("Fresnel, dielectric: normal incidence, 45 degrees, grazing", Real, float, double) {
    const Real n = Real(1.5);
    // Normal incidence: ((n - 1) / (n + 1))^2 = 0.04, from either side.
    CHECK(prism::fresnel_dielectric<Real>(1, 1, 1, n) == doctest::Approx(0.04).epsilon(tolerance<Real>));
    CHECK(prism::fresnel_dielectric<Real>(1, 1, n, 1) == doctest::Approx(0.04).epsilon(tolerance<Real>));

    // Air to glass at 45 degrees: Rs = 0.0920, Rp = 0.0085 (published, e.g. Hecht's tables).
    const double theta = quarter_turn / 2;
    const Reflectance exact = dielectric_reflectance(theta, 1.0, 1.5);
    CHECK(exact.s == doctest::Approx(0.0920).epsilon(1e-3));
    CHECK(exact.p == doctest::Approx(0.0085).epsilon(1e-2));
    const Real cos_i = Real(std::cos(theta)), cos_t = Real(cos_transmitted(theta, 1.0, 1.5));
    CHECK(std::abs(double(prism::fresnel_dielectric<Real>(cos_i, cos_t, 1, n)) - exact.average()) < 1e-4);
    CHECK(prism::fresnel_dielectric<Real>(cos_i, cos_t, 1, n) == doctest::Approx(0.05024).epsilon(1e-3));

    // Grazing: everything is reflected.
    const Real cos_t_grazing = Real(cos_transmitted(quarter_turn, 1.0, 1.5));
    CHECK(prism::fresnel_dielectric<Real>(0, cos_t_grazing, 1, n) == doctest::Approx(1).epsilon(tolerance<Real>));
}

TEST_CASE_TEMPLATE("Fresnel, dielectric: every angle against the exact equations, reciprocity", Real, float, double) {
    double previous = 0;
    for (int degrees = 0; degrees < 90; degrees += 5) {
        CAPTURE(degrees);
        const double theta = degrees * quarter_turn / 90;
        const Real cos_i = Real(std::cos(theta)), cos_t = Real(cos_transmitted(theta, 1.0, 1.5));
        const double reflectance = double(prism::fresnel_dielectric<Real>(cos_i, cos_t, 1, Real(1.5)));
        CHECK(std::abs(reflectance - dielectric_reflectance(theta, 1.0, 1.5).average()) < 1e-5);
        // Light going the other way (glass to air along the transmitted direction) reflects as much.
        CHECK(double(prism::fresnel_dielectric<Real>(cos_t, cos_i, Real(1.5), 1)) ==
              doctest::Approx(reflectance).epsilon(1e-5));
        // From outside, unpolarised reflectance grows monotonically towards grazing.
        CHECK(reflectance > previous);
        previous = reflectance;
    }
}

TEST_CASE_TEMPLATE("Fresnel, conductor: gold-like n = 0.47, k = 2.83", Real, float, double) {
    const Real n = Real(0.47), k = Real(2.83);
    // Normal incidence: ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2) = 0.815139.
    const double normal = ((0.47 - 1) * (0.47 - 1) + 2.83 * 2.83) / ((0.47 + 1) * (0.47 + 1) + 2.83 * 2.83);
    CHECK(normal == doctest::Approx(0.815139).epsilon(1e-6));
    CHECK(prism::fresnel_conductor<Real>(1, n, k) == doctest::Approx(normal).epsilon(tolerance<Real>));
    CHECK(prism::fresnel_conductor<Real>(1, n, k) == doctest::Approx(conductor_reflectance_exact(1, 0.47, 2.83)).epsilon(1e-5));
    // Grazing: 1.
    CHECK(prism::fresnel_conductor<Real>(0, n, k) == doctest::Approx(1).epsilon(tolerance<Real>));
    // In between, the course's approximation stays within 0.01 of the exact complex Fresnel.
    for (int degrees = 10; degrees < 90; degrees += 10) {
        CAPTURE(degrees);
        const double cos_i = std::cos(degrees * quarter_turn / 90);
        CHECK(std::abs(double(prism::fresnel_conductor<Real>(Real(cos_i), n, k)) -
                       conductor_reflectance_exact(cos_i, 0.47, 2.83)) < 0.01);
    }
    // With no absorption a conductor is a dielectric of index n: 0.04 for n = 1.5.
    CHECK(prism::fresnel_conductor<Real>(1, Real(1.5), 0) == doctest::Approx(0.04).epsilon(tolerance<Real>));
}

// ---------------------------------------------------------------------------------------------
// Pinhole camera

TEST_CASE_TEMPLATE("PinholeCamera: rays through pixel centres", Real, float, double) {
    using V = prism::Vec3<Real>;
    scene::Camera camera;
    camera.position = {1, 2, 3};
    camera.gaze = {0, 0, -2};  // not unit: only its direction counts
    camera.up = {0, 1, 0};
    camera.near_left = -2;
    camera.near_right = 2;
    camera.near_bottom = -1;
    camera.near_top = 1;
    camera.near_distance = 1;
    camera.width = 4;
    camera.height = 2;
    auto expect_direction = [](const prism::Ray<Real>& ray, glm::dvec3 direction) {
        direction = glm::normalize(direction);
        CHECK(ray.direction.x == doctest::Approx(direction.x).epsilon(tolerance<Real>));
        CHECK(ray.direction.y == doctest::Approx(direction.y).epsilon(tolerance<Real>));
        CHECK(ray.direction.z == doctest::Approx(direction.z).epsilon(tolerance<Real>));
        CHECK(double(glm::length(ray.direction)) == doctest::Approx(1).epsilon(tolerance<Real>));
    };

    SUBCASE("right-handed: top-left pixel centre and image centre") {
        const prism::PinholeCamera<Real> pinhole(camera, camera.width, camera.height);
        CHECK(pinhole.width() == 4);
        CHECK(pinhole.height() == 2);
        const auto top_left = pinhole.ray(Real(0.5), Real(0.5));
        CHECK(top_left.origin == V(1, 2, 3));
        CHECK(top_left.t_min == Real(0));
        // Pixels are 1 x 1 on the near plane: the first centre is half a pixel in from (l, t).
        expect_direction(top_left, {-1.5, 0.5, -1});
        expect_direction(pinhole.ray(Real(2), Real(1)), {0, 0, -1});
        expect_direction(pinhole.ray(Real(3.5), Real(1.5)), {1.5, -0.5, -1});  // bottom-right centre
    }
    SUBCASE("left-handed: u flips, so the image is mirrored horizontally") {
        camera.left_handed = true;
        const prism::PinholeCamera<Real> pinhole(camera, camera.width, camera.height);
        expect_direction(pinhole.ray(Real(0.5), Real(0.5)), {1.5, 0.5, -1});
        expect_direction(pinhole.ray(Real(2), Real(1)), {0, 0, -1});
    }
    SUBCASE("looking along +x: u = up x w = +z") {
        camera.gaze = {1, 0, 0};
        const prism::PinholeCamera<Real> pinhole(camera, camera.width, camera.height);
        expect_direction(pinhole.ray(Real(0.5), Real(0.5)), {1, 0.5, -1.5});
        camera.left_handed = true;
        const prism::PinholeCamera<Real> mirrored(camera, camera.width, camera.height);
        expect_direction(mirrored.ray(Real(0.5), Real(0.5)), {1, 0.5, 1.5});
    }
    SUBCASE("an up vector not perpendicular to the gaze is orthogonalised") {
        camera.up = {0, 1, 1};
        const prism::PinholeCamera<Real> pinhole(camera, camera.width, camera.height);
        expect_direction(pinhole.ray(Real(0.5), Real(0.5)), {-1.5, 0.5, -1});
    }
    SUBCASE("a reduced resolution covers the same near plane with larger pixels") {
        const prism::PinholeCamera<Real> half(camera, 2, 1);
        expect_direction(half.ray(Real(0.5), Real(0.5)), {-1, 0, -1});
        expect_direction(half.ray(Real(1), Real(0.5)), {0, 0, -1});
    }
}

// ---------------------------------------------------------------------------------------------
// Rendering tiny scenes

namespace {

// The course's Blinn-Phong at one point, in double: ka Ia + kd cos(theta) I/d^2 +
// ks (n.h)^p I/d^2, with no shadow test.
glm::dvec3 blinn_phong(const glm::dvec3& point, const glm::dvec3& normal, const glm::dvec3& to_viewer,
                       const scene::Material& material, const scene::PointLight& light,
                       const glm::dvec3& ambient_light) {
    const glm::dvec3 to_light = light.position - point;
    const double distance_squared = glm::dot(to_light, to_light);
    const glm::dvec3 l = to_light / std::sqrt(distance_squared);
    const glm::dvec3 irradiance = light.intensity / distance_squared;
    const double cos_theta = glm::dot(normal, l);
    const glm::dvec3 h = glm::normalize(l + to_viewer);
    return material.ambient * ambient_light + material.diffuse * cos_theta * irradiance +
           material.specular * std::pow(glm::dot(normal, h), material.phong_exponent) * irradiance;
}

// A camera at the origin looking down -z at a 3 x 3 image: the centre pixel's ray is -z.
scene::Camera centre_camera() {
    scene::Camera camera;
    camera.near_left = camera.near_bottom = -0.1;
    camera.near_right = camera.near_top = 0.1;
    camera.near_distance = 1;
    camera.width = camera.height = 3;
    return camera;
}

// A triangle in the plane z = -2 around (0, 0, -2), facing the camera (+z).
scene::Mesh facing_triangle(std::size_t material) {
    scene::Mesh mesh;
    mesh.material = material;
    mesh.positions = {{-1, -1, -2}, {1, -1, -2}, {0, 1, -2}};
    mesh.triangles = {{0, 1, 2}};
    return mesh;
}

scene::Material matte() {
    scene::Material material;
    material.ambient = {0.1, 0.2, 0.3};
    material.diffuse = {0.5, 0.4, 0.3};
    material.specular = {0.2, 0.2, 0.2};
    material.phong_exponent = 10;
    return material;
}

// One point light at (1, 2, 0): 3 units from (0, 0, -2), cos(theta) = 2/3, I/d^2 = 100.
scene::Scene lit_scene() {
    scene::Scene world;
    world.ambient_light = {10, 20, 30};
    world.background_color = {5, 6, 7};
    world.max_recursion_depth = 2;
    world.cameras.push_back(centre_camera());
    world.point_lights.push_back({"key", {1, 2, 0}, {900, 900, 900}});
    world.materials.push_back(matte());
    world.meshes.push_back(facing_triangle(0));
    return world;
}

template <class Real>
glm::dvec3 centre_pixel(const scene::Scene& world) {
    const prism::Renderer<prism::Config<Real>> renderer(world);
    const prism::Image image = renderer.render(world.cameras[0]);
    REQUIRE(image.width == 3);
    REQUIRE(image.height == 3);
    return glm::dvec3(image(1, 1));
}

void check_relative(const glm::dvec3& actual, const glm::dvec3& expected, double relative) {
    for (int c = 0; c < 3; ++c) {
        CAPTURE(c);
        CHECK(actual[c] == doctest::Approx(expected[c]).epsilon(relative));
    }
}

}  // namespace

TEST_CASE_TEMPLATE("Renderer: Blinn-Phong under one point light equals the hand computation", Real, float, double) {
    const scene::Scene world = lit_scene();
    const glm::dvec3 expected = blinn_phong({0, 0, -2}, {0, 0, 1}, {0, 0, 1}, world.materials[0],
                                            world.point_lights[0], world.ambient_light);
    // By hand: ka Ia = (1, 4, 9); kd (2/3) 100 = (33.33, 26.67, 20); h = (1, 2, 5)/sqrt(30),
    // 0.2 (5/sqrt(30))^10 100 = 8.0376.
    CHECK(expected.x == doctest::Approx(1 + 100.0 / 3 + 8.0376).epsilon(1e-4));
    CHECK(expected.z == doctest::Approx(9 + 20 + 8.0376).epsilon(1e-4));
    check_relative(centre_pixel<Real>(world), expected, 1e-4);
    // The same through Renderer::radiance with the exact centre ray.
    const prism::Renderer<prism::Config<Real>> renderer(world);
    const prism::Ray<Real> ray{prism::Vec3<Real>(0), prism::Vec3<Real>(0, 0, -1)};
    check_relative(glm::dvec3(renderer.radiance(ray)), expected, 1e-4);
    // A primary ray that escapes brings the background.
    check_relative(glm::dvec3(renderer.radiance({prism::Vec3<Real>(0), prism::Vec3<Real>(0, 1, 0)})),
                   world.background_color, 1e-6);
}

TEST_CASE_TEMPLATE("Renderer: without a specular colour, ambient and diffuse only, at every exponent", Real, float,
                   double) {
    // The integrator skips the power for such a material; a negative exponent still takes it.
    for (double exponent : {10.0, 0.0, 1e9, -2.0}) {
        CAPTURE(exponent);
        scene::Scene world = lit_scene();
        world.materials[0].specular = {0, 0, 0};
        world.materials[0].phong_exponent = exponent;
        const glm::dvec3 expected = world.materials[0].ambient * world.ambient_light +
                                    world.materials[0].diffuse * (2.0 / 3) * 100.0;
        check_relative(centre_pixel<Real>(world), expected, 1e-4);
    }
}

TEST_CASE_TEMPLATE("Renderer: a sphere between the light and the point leaves ambient only", Real, float, double) {
    scene::Scene world = lit_scene();
    // Centred on the segment from (0, 0, -2) to the light, clear of the camera's centre ray.
    world.spheres.push_back({"blocker", 0, {0.5, 1, -1}, 0.3, glm::dmat4(1.0)});
    const glm::dvec3 ambient = world.materials[0].ambient * world.ambient_light;
    check_relative(centre_pixel<Real>(world), ambient, 1e-4);
    // The shadow is the sphere's doing: moved aside, the full shading returns.
    world.spheres[0].center = {3, 1, -1};
    check_relative(centre_pixel<Real>(world),
                   blinn_phong({0, 0, -2}, {0, 0, 1}, {0, 0, 1}, world.materials[0], world.point_lights[0],
                               world.ambient_light),
                   1e-4);
}

TEST_CASE_TEMPLATE("Renderer: a mirror adds km times the radiance of the reflected ray", Real, float, double) {
    // The triangle at z = -2 is a mirror (with a little ambient of its own); the reflected
    // centre ray goes back along +z to a matte triangle at z = +1, behind the camera.
    scene::Scene world = lit_scene();
    scene::Material mirror;
    mirror.type = scene::MaterialType::mirror;
    mirror.ambient = {0.1, 0.1, 0.1};
    mirror.mirror = {0.5, 0.6, 0.7};
    world.materials.push_back(mirror);
    world.meshes[0].material = 1;
    scene::Mesh back = facing_triangle(0);
    for (auto& p : back.positions) p.z = 1;
    world.meshes.push_back(back);

    const glm::dvec3 own = mirror.ambient * world.ambient_light;
    // At (0, 0, 1) the matte triangle is seen along +z from below: its normal towards the
    // viewer is -z, and the light at (1, 2, 0) is on that side.
    const glm::dvec3 reflected = blinn_phong({0, 0, 1}, {0, 0, -1}, {0, 0, -1}, world.materials[0],
                                             world.point_lights[0], world.ambient_light);

    SUBCASE("depth 2: own ambient plus km times the reflection, by hand") {
        check_relative(centre_pixel<Real>(world), own + mirror.mirror * reflected, 1e-4);
        // And km times what the renderer itself sees along the reflected ray.
        // radiance() traces its ray as a camera ray, which skips the flat triangle's back face by
        // default; the reflected ray sees it, so compare with the renderer that culls nothing.
        const prism::Renderer<prism::Config<Real>> renderer(world, {prism::BackfaceCulling::none});
        const prism::Ray<Real> reflected_ray{prism::Vec3<Real>(0, 0, Real(-2 + world.shadow_ray_epsilon)),
                                             prism::Vec3<Real>(0, 0, 1)};
        check_relative(centre_pixel<Real>(world), own + mirror.mirror * glm::dvec3(renderer.radiance(reflected_ray)),
                       1e-4);
    }
    SUBCASE("depth 0: no reflection at all") {
        world.max_recursion_depth = 0;
        check_relative(centre_pixel<Real>(world), own, 1e-4);
    }
    SUBCASE("a reflected ray that escapes brings nothing, not the background") {
        world.meshes.pop_back();
        check_relative(centre_pixel<Real>(world), own, 1e-4);
    }
}

TEST_CASE_TEMPLATE("Renderer: camera rays skip a back face, flat or smooth, as the course does", Real, float, double) {
    // A small triangle at z = -1 wound to face away from the camera, between the camera and the
    // lit triangle at z = -2, and clear of the lit point's shadow ray towards (1, 2, 0).
    scene::Scene world = lit_scene();
    scene::Material occluder_material = matte();
    occluder_material.ambient = {0.9, 0.1, 0.1};
    occluder_material.diffuse = {0.1, 0.6, 0.1};
    world.materials.push_back(occluder_material);
    scene::Mesh occluder;
    occluder.material = 1;
    occluder.positions = {{-0.5, -0.5, -1}, {0, 0.5, -1}, {0.5, -0.5, -1}};  // clockwise from the camera
    occluder.triangles = {{0, 1, 2}};
    world.meshes.push_back(occluder);

    const glm::dvec3 lit = blinn_phong({0, 0, -2}, {0, 0, 1}, {0, 0, 1}, world.materials[0], world.point_lights[0],
                                       world.ambient_light);
    // Seen, the back face is shaded on the camera's side (normal +z), under the same light.
    const glm::dvec3 back_face = blinn_phong({0, 0, -1}, {0, 0, 1}, {0, 0, 1}, occluder_material,
                                             world.point_lights[0], world.ambient_light);
    REQUIRE(glm::length(lit - back_face) > 10);  // the two outcomes are told apart

    const auto centre = [&](prism::BackfaceCulling culling) {
        const prism::Renderer<prism::Config<Real>> renderer(world, {culling});
        return glm::dvec3(renderer.render(world.cameras[0])(1, 1));
    };
    // The default, --cull-backfaces too, skip it whatever its shading (issue 30: the held-out
    // smooth windmill); --no-cull-backfaces shows it.
    for (const auto shading : {scene::ShadingMode::flat, scene::ShadingMode::smooth}) {
        world.meshes.back().shading = shading;
        CAPTURE(int(shading));
        check_relative(centre_pixel<Real>(world), lit, 1e-4);
        check_relative(centre(prism::BackfaceCulling::triangles), lit, 1e-4);
        check_relative(centre(prism::BackfaceCulling::all), lit, 1e-4);
        check_relative(centre(prism::BackfaceCulling::none), back_face, 1e-4);
    }
    SUBCASE("turned to face the camera, it hides the lit triangle whatever the rule") {
        std::swap(world.meshes.back().triangles[0][1], world.meshes.back().triangles[0][2]);
        for (const auto culling : {prism::BackfaceCulling::none, prism::BackfaceCulling::triangles,
                                   prism::BackfaceCulling::all})
            check_relative(centre(culling), back_face, 1e-4);
    }
}

TEST_CASE_TEMPLATE("Renderer: a scene built in code is held to the loaders' limits", Real, float, double) {
    // The loaders refuse these in files (io/limits.hpp, test_hostile_input.cpp); a program that
    // builds its scene in code must meet the same wall, with a message, not a crashed stack or a
    // film too large to allocate.
    scene::Scene world = lit_scene();
    using Renderer = prism::Renderer<prism::Config<Real>>;
    world.max_recursion_depth = prism::io::stack_safe_recursion_depth;
    CHECK_NOTHROW(Renderer{world});
    world.max_recursion_depth = prism::io::stack_safe_recursion_depth + 1;
    CHECK_THROWS_WITH_AS(Renderer{world}, doctest::Contains("MaxRecursionDepth 513"), std::invalid_argument);
    world.max_recursion_depth = -1;
    CHECK_THROWS_AS(Renderer{world}, std::invalid_argument);

    world.max_recursion_depth = 1;
    const Renderer renderer(world);
    scene::Camera camera = world.cameras.front();
    CHECK_THROWS_WITH_AS(renderer.render(camera, 40000, 1), doctest::Contains("40000x1"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(renderer.render(camera, 20000, 20000), doctest::Contains("outside the limits"),
                         std::invalid_argument);
    camera.num_samples = int(prism::io::max_samples_per_pixel) + 1;
    CHECK_THROWS_WITH_AS(renderer.render(camera, 2, 2), doctest::Contains("samples per pixel"), std::invalid_argument);
    camera.num_samples = 1;
    CHECK(renderer.render(camera, 2, 2).pixels.size() == 4);
}

TEST_CASE_TEMPLATE("stored_whole hands on the same ray, bit for bit", Real, float, double) {
    // Every field in its place: a lane out of order (origin and direction swapped, t_min and
    // t_max, the time left out) changes a field below.
    const auto same = [](Real a, Real b) { return std::memcmp(&a, &b, sizeof(Real)) == 0; };
    const auto check = [&](const prism::Ray<Real>& ray) {
        const prism::Ray<Real> whole = prism::stored_whole(ray);
        for (int axis = 0; axis < 3; ++axis) {
            CHECK(same(whole.origin[axis], ray.origin[axis]));
            CHECK(same(whole.direction[axis], ray.direction[axis]));
        }
        CHECK(same(whole.t_min, ray.t_min));
        CHECK(same(whole.t_max, ray.t_max));
        CHECK(same(whole.time, ray.time));
    };
    std::mt19937 random(21);
    std::uniform_real_distribution<double> uniform(-100, 100);
    for (int i = 0; i < 1000; ++i) {
        prism::Ray<Real> ray;
        ray.origin = prism::Vec3<Real>(Real(uniform(random)), Real(uniform(random)), Real(uniform(random)));
        ray.direction = prism::Vec3<Real>(Real(uniform(random)), Real(uniform(random)), Real(uniform(random)));
        ray.t_min = Real(uniform(random));
        ray.t_max = Real(uniform(random));
        ray.time = Real(uniform(random));
        check(ray);
    }
    // Signed zeros, infinities and NaNs pass as they are.
    const Real nan = std::numeric_limits<Real>::quiet_NaN();
    check({prism::Vec3<Real>(Real(-0.0), Real(0), nan), prism::Vec3<Real>(Real(1), Real(-0.0), Real(0)), Real(-0.0),
           std::numeric_limits<Real>::infinity(), nan});
}
