// Environment lights through the whole renderer, for float and double: the white furnace (a
// diffuse sphere under a constant environment renders its albedo times the environment, with
// uniform, cosine and importance sampling) and one procedural sky in lat-long and light-probe
// layouts rendering the same image within noise.
#include <prism/light/procedural_sky.hpp>
#include <prism/render/render_scene.hpp>
#include <prism/render/renderer.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <memory>

namespace {

namespace scene = prism::scene;
using Layout = scene::EnvironmentLayout;
using Sampling = scene::EnvironmentSampling;

template <class Real>
using Complete = prism::Config<Real, prism::Bvh<prism::Watertight>, prism::AllLightSet, prism::all_features>;

// A unit sphere seen whole by a camera on +z, lit by one environment light from `image`.
scene::Scene sphere_under(const prism::Image& image, Layout layout, Sampling sampling, double kd, int samples) {
    scene::Scene world;
    scene::Camera camera;
    camera.position = {0, 0, 5};
    camera.gaze = {0, 0, -1};
    camera.near_left = camera.near_bottom = -0.25;
    camera.near_right = camera.near_top = 0.25;
    camera.near_distance = 1;
    camera.width = camera.height = 24;
    camera.num_samples = samples;
    world.cameras.push_back(camera);
    scene::Material matte;
    matte.diffuse = glm::dvec3(kd);
    world.materials.push_back(matte);
    world.spheres.push_back({"ball", 0, {0, 0, 0}, 1, glm::dmat4(1.0)});
    world.images.push_back({"environment.exr", std::make_shared<const prism::Texels>(image), true});
    world.environment_lights.push_back({"sky", 0, layout, sampling, {1, 1, 1}});
    return world;
}

// Mean radiance of the pixels whose centre ray hits the sphere well inside its outline, and of
// the pixels that miss it entirely (the background).
struct Means {
    glm::dvec3 sphere{0}, background{0};
};
Means pixel_means(const prism::Image& image) {
    Means means;
    int inside = 0, outside = 0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x) {
            // The image spans 1.25 units at the sphere's distance: radius 1 is 0.8 of the half-width.
            const double u = (x + 0.5) / image.width * 2 - 1, v = (y + 0.5) / image.height * 2 - 1;
            const double r = std::sqrt(u * u + v * v) * 1.25;
            if (r < 0.85) {
                means.sphere += glm::dvec3(image(x, y));
                ++inside;
            } else if (r > 1.15) {
                means.background += glm::dvec3(image(x, y));
                ++outside;
            }
        }
    means.sphere /= double(inside);
    means.background /= double(outside);
    return means;
}

}  // namespace

TEST_CASE_TEMPLATE("white furnace: a diffuse sphere of albedo rho under a constant L renders rho L", Real, float,
                   double) {
    // The course's diffuse term kd cos L / pdf averages to pi kd L: albedo rho means kd = rho / pi.
    const double rho = 0.6, radiance = 2.5;
    for (const Layout layout : {Layout::latlong, Layout::probe}) {
        const prism::Image constant = prism::render_constant(glm::dvec3(radiance), layout, 64);
        for (const Sampling sampling : {Sampling::uniform, Sampling::cosine, Sampling::importance}) {
            CAPTURE(int(layout));
            CAPTURE(int(sampling));
            const scene::Scene world = sphere_under(constant, layout, sampling, rho / prism::pi<double>, 64);
            const prism::Renderer<Complete<Real>> renderer(world);
            const Means means = pixel_means(renderer.render(world.cameras[0]));
            for (int c = 0; c < 3; ++c) {
                CHECK(means.sphere[c] == doctest::Approx(rho * radiance).epsilon(0.01));
                // The environment is also the background.
                CHECK(means.background[c] == doctest::Approx(radiance).epsilon(1e-3));
            }
        }
    }
}

TEST_CASE_TEMPLATE("one sky in lat-long and probe layouts renders the same image within noise", Real, float, double) {
    prism::ProceduralSky sky;
    sky.sun_direction = {1, 1.2, 0.6};
    sky.sun_angle_degrees = 8;  // a large sun, so both layouts resolve it
    sky.sun_radiance = {40, 36, 30};
    prism::Image images[2];
    int index = 0;
    for (const Layout layout : {Layout::latlong, Layout::probe}) {
        const prism::Image map = prism::render_sky(sky, layout, layout == Layout::latlong ? 256 : 192);
        const scene::Scene world = sphere_under(map, layout, Sampling::importance, 0.5 / prism::pi<double>, 64);
        const prism::Renderer<Complete<Real>> renderer(world);
        images[index++] = renderer.render(world.cameras[0]);
    }
    const Means latlong = pixel_means(images[0]), probe = pixel_means(images[1]);
    for (int c = 0; c < 3; ++c) {
        CHECK(latlong.sphere[c] == doctest::Approx(probe.sphere[c]).epsilon(0.02));
        CHECK(latlong.background[c] == doctest::Approx(probe.background[c]).epsilon(0.02));
    }
    // Pixel by pixel: the mean absolute difference is a small share of the mean radiance.
    double difference = 0, total = 0;
    for (std::size_t i = 0; i < images[0].pixels.size(); ++i) {
        difference += glm::length(glm::dvec3(images[0].pixels[i]) - glm::dvec3(images[1].pixels[i]));
        total += glm::length(glm::dvec3(images[0].pixels[i]));
    }
    CHECK(difference / total < 0.05);
}
