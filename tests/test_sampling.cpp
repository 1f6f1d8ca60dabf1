// The course's distribution ray tracing, for float and double: the per-pixel random streams,
// stratified camera samples, the reconstruction filter, the thin lens, area lights, motion blur
// (moving boxes and rays at an instant), roughness, and images bit-identical at 1 and 2 threads.
#include "one_by_one_pixel.hpp"

#include <prism/camera/pixel_sampler.hpp>
#include <prism/camera/thin_lens_camera.hpp>
#include <prism/light/area_light.hpp>
#include <prism/render/render_scene.hpp>
#include <prism/render/renderer.hpp>
#include <prism/sampling/random.hpp>

#include <doctest/doctest.h>

#include <tbb/global_control.h>

#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <type_traits>
#include <vector>

namespace {

namespace scene = prism::scene;

scene::Camera looking_down_z(int width, int height) {
    scene::Camera camera;
    camera.position = {0, 0, 10};
    camera.gaze = {0, 0, -1};
    camera.up = {0, 1, 0};
    camera.near_left = camera.near_bottom = -1;
    camera.near_right = camera.near_top = 1;
    camera.near_distance = 2;
    camera.width = width;
    camera.height = height;
    return camera;
}

scene::Material matte(double albedo) {
    scene::Material material;
    material.diffuse = glm::dvec3(albedo);
    return material;
}

// A ridged sheet of 72 triangles, transformed (rotated and moved behind the test scenes' balls):
// a scene that holds it keeps its top-level index.
scene::Mesh ridged_tent(std::size_t material) {
    scene::Mesh tent;
    tent.material = material;
    for (int z = 0; z <= 6; ++z)
        for (int x = 0; x <= 6; ++x) tent.positions.push_back({x / 3.0 - 1, ((x + z) % 2) * 0.2, z / 3.0 - 1});
    for (std::uint32_t z = 0; z < 6; ++z)
        for (std::uint32_t x = 0; x < 6; ++x) {
            const std::uint32_t a = z * 7 + x;
            tent.triangles.push_back({a, a + 7, a + 8});
            tent.triangles.push_back({a, a + 8, a + 1});
        }
    tent.transform = glm::translate(glm::dmat4(1.0), glm::dvec3(2.8, 1.5, -3)) *
                     glm::rotate(glm::dmat4(1.0), 1.2, glm::dvec3(1, 0.2, 0));
    return tent;
}

}  // namespace

TEST_CASE_TEMPLATE("Random: reproducible per pixel, uniform in [0, 1), streams differ", Real, float, double) {
    prism::Random a = prism::Random::for_pixel(3, 7, 42), b = prism::Random::for_pixel(3, 7, 42);
    prism::Random other_pixel = prism::Random::for_pixel(4, 7, 42), other_seed = prism::Random::for_pixel(3, 7, 43);
    int same_as_other_pixel = 0, same_as_other_seed = 0;
    double sum = 0;
    constexpr int count = 100000;
    for (int i = 0; i < count; ++i) {
        const Real u = a.uniform<Real>();
        REQUIRE(u == b.uniform<Real>());
        REQUIRE(u >= Real(0));
        REQUIRE(u < Real(1));
        same_as_other_pixel += u == other_pixel.uniform<Real>();
        same_as_other_seed += u == other_seed.uniform<Real>();
        sum += double(u);
    }
    CHECK(same_as_other_pixel < 10);
    CHECK(same_as_other_seed < 10);
    // Mean of 10^5 uniforms: standard deviation 1/sqrt(12 * 10^5) = 0.0009.
    CHECK(sum / count == doctest::Approx(0.5).epsilon(0.01));
}

TEST_CASE_TEMPLATE("camera_samples: a jittered grid for square counts, n-rooks otherwise", Real, float, double) {
    prism::Random random = prism::Random::for_pixel(0, 0, 1);
    std::vector<prism::CameraSample<Real>> samples;
    std::vector<prism::Vec2<Real>> scratch;
    SUBCASE("16 samples: one in each cell of a 4 x 4 grid, for the pixel and the lens; one per time stratum") {
        prism::camera_samples(16, random, samples, scratch);
        REQUIRE(samples.size() == 16);
        std::set<int> pixel_cells, lens_cells, time_strata;
        for (const auto& sample : samples) {
            pixel_cells.insert(int(sample.pixel.x * 4) + 4 * int(sample.pixel.y * 4));
            lens_cells.insert(int(sample.lens.x * 4) + 4 * int(sample.lens.y * 4));
            time_strata.insert(int(sample.time * 16));
        }
        CHECK(pixel_cells.size() == 16);
        CHECK(lens_cells.size() == 16);
        CHECK(time_strata.size() == 16);
    }
    SUBCASE("6 samples: each row and each column of a 6 x 6 grid once") {
        prism::camera_samples(6, random, samples, scratch);
        std::set<int> rows, columns;
        for (const auto& sample : samples) {
            columns.insert(int(sample.pixel.x * 6));
            rows.insert(int(sample.pixel.y * 6));
        }
        CHECK(rows.size() == 6);
        CHECK(columns.size() == 6);
    }
    SUBCASE("one sample: the pixel centre") {
        prism::camera_samples(1, random, samples, scratch);
        CHECK(samples[0].pixel == prism::Vec2<Real>(Real(0.5)));
    }
}

TEST_CASE("Random::advance(k) leaves the stream where k outputs leave it") {
    for (const std::uint64_t steps : {0ull, 1ull, 2ull, 3ull, 7ull, 64ull, 199ull, 1000ull, 123457ull}) {
        prism::Random stepped = prism::Random::for_pixel(3, 5, 11), advanced = stepped;
        for (std::uint64_t i = 0; i < steps; ++i) stepped.next_u32();
        advanced.advance(steps);
        CAPTURE(steps);
        for (int i = 0; i < 4; ++i) CHECK(advanced.next_u32() == stepped.next_u32());
    }
}

TEST_CASE_TEMPLATE("camera_samples: parts the render does not read are not made, and the stream goes on as if they were",
                   Real, float, double) {
    // Square and non-square counts (the n-rooks grid draws its shuffle too), each with the lens,
    // the instant, both or neither left out: the pixel positions are the full draw's, the parts
    // left out keep CameraSample's defaults, and the stream's next draws are the full draw's.
    for (const int count : {2, 4, 6, 16, 25, 100}) {
        for (const prism::CameraReads reads : {prism::CameraReads{false, false}, prism::CameraReads{true, false},
                                               prism::CameraReads{false, true}, prism::CameraReads{true, true}}) {
            CAPTURE(count);
            CAPTURE(reads.lens);
            CAPTURE(reads.time);
            prism::Random full = prism::Random::for_pixel(7, 2, 5), partial = full;
            std::vector<prism::CameraSample<Real>> all, some;
            std::vector<prism::Vec2<Real>> scratch;
            prism::camera_samples(count, full, all, scratch);
            prism::camera_samples(count, partial, some, scratch, reads);
            REQUIRE(some.size() == all.size());
            for (std::size_t i = 0; i < all.size(); ++i) {
                CHECK(some[i].pixel == all[i].pixel);
                CHECK(some[i].lens == (reads.lens ? all[i].lens : prism::Vec2<Real>(Real(0.5))));
                CHECK(some[i].time == (reads.time ? all[i].time : Real(0)));
            }
            for (int i = 0; i < 3; ++i) CHECK(partial.next_u32() == full.next_u32());
        }
    }
}

TEST_CASE_TEMPLATE("filter_weight: box is flat, the Gaussian has sigma 1/2 pixel", Real, float, double) {
    using prism::Vec2;
    CHECK(prism::filter_weight(scene::PixelFilter::box, Vec2<Real>(Real(0.1), Real(0.9))) == Real(1));
    CHECK(prism::filter_weight(scene::PixelFilter::gaussian, Vec2<Real>(Real(0.5))) == Real(1));
    // At the corner: d^2 = 1/2, exp(-(1/2) / (2 * 1/4)) = e^-1.
    CHECK(double(prism::filter_weight(scene::PixelFilter::gaussian, Vec2<Real>(Real(0)))) ==
          doctest::Approx(std::exp(-1.0)).epsilon(1e-6));
}

TEST_CASE_TEMPLATE("ThinLensCamera: every lens ray meets the pinhole ray on the plane of focus", Real, float, double) {
    scene::Camera camera = looking_down_z(8, 8);
    camera.aperture_size = 0.5;
    camera.focus_distance = 6;
    const prism::ThinLensCamera<Real> lens(camera, 8, 8);
    const prism::PinholeCamera<Real> pinhole(camera, 8, 8);
    for (const prism::Vec2<Real> image : {prism::Vec2<Real>(Real(4), Real(4)), prism::Vec2<Real>(Real(0.5), Real(7.5))}) {
        const prism::Ray<Real> centre = pinhole.ray(image.x, image.y);
        // The plane of focus is z = 10 - 6 = 4 (the gaze is -z).
        const prism::Vec3<Real> focus = centre.at((Real(10) - Real(4)) / -centre.direction.z);
        for (const prism::Vec2<Real> at : {prism::Vec2<Real>(Real(0), Real(0)), prism::Vec2<Real>(Real(0.99), Real(0.3))}) {
            const prism::Ray<Real> ray = lens.ray(image.x, image.y, at, Real(0.25));
            CHECK(ray.time == Real(0.25));
            CHECK(double(glm::length(ray.direction)) == doctest::Approx(1).epsilon(1e-6));
            // The origin lies on the aperture square, within ApertureSize / 2 of the centre.
            CHECK(double(ray.origin.z) == doctest::Approx(10));
            CHECK(std::abs(double(ray.origin.x)) <= 0.25 + 1e-6);
            const prism::Vec3<Real> reached = ray.at((Real(10) - Real(4)) / -ray.direction.z);
            for (int axis = 0; axis < 3; ++axis)
                CHECK(double(reached[axis]) == doctest::Approx(double(focus[axis])).epsilon(1e-5).scale(1));
        }
    }
    // No aperture: the pinhole ray itself.
    camera.aperture_size = 0;
    const prism::ThinLensCamera<Real> pinhole_lens(camera, 8, 8);
    const prism::Ray<Real> ray = pinhole_lens.ray(Real(2.5), Real(3.5), prism::Vec2<Real>(Real(0.9)), Real(0));
    CHECK(ray.origin == pinhole.ray(Real(2.5), Real(3.5)).origin);
    CHECK(ray.direction == pinhole.ray(Real(2.5), Real(3.5)).direction);
}

TEST_CASE_TEMPLATE("AreaLight: the estimate averages to the irradiance of the square, from both sides", Real, float,
                   double) {
    scene::Scene world;
    // A 2 x 2 square at height 3 facing up (away from the point), centred above the origin.
    world.area_lights.push_back({"panel", {-1, 3, -1}, {2, 0, 0}, {0, 0, 2}, {10, 10, 10}});
    const auto lights = prism::AreaLight<Real>::from_scene(world);
    REQUIRE(lights.size() == 1);
    CHECK(double(lights[0].area) == doctest::Approx(4));
    // Irradiance-like quantity the course integrates: L * integral over the square of
    // cos_light / d^2 dA, computed here by a fine midpoint rule in double.
    double expected = 0;
    constexpr int n = 400;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double x = -1 + 2 * (i + 0.5) / n, z = -1 + 2 * (j + 0.5) / n;
            const double d2 = x * x + 9 + z * z;
            expected += 10 * (3 / std::sqrt(d2)) / d2 * (4.0 / (n * n));
        }
    prism::Random random(7);
    double sum = 0;
    constexpr int samples = 200000;
    for (int s = 0; s < samples; ++s) {
        const auto sample = lights[0].sample({prism::Vec3<Real>(0), prism::Vec3<Real>(0, 1, 0)}, random.uniform2<Real>());
        sum += double(sample.radiance.r);
    }
    CHECK(sum / samples == doctest::Approx(expected).epsilon(0.005));
}

TEST_CASE_TEMPLATE("Motion blur: the box covers the sweep, rays meet the object where it is at their instant", Real,
                   float, double) {
    scene::Scene world;
    world.materials.push_back(matte(0.5));
    scene::Sphere sphere{"moving", 0, {0, 0, 0}, 1, glm::dmat4(1.0)};
    sphere.motion = {10, 0, 0};
    world.spheres.push_back(sphere);
    const prism::SceneGeometry<Real, prism::Bvh<prism::Watertight>, true> geometry(world);
    const prism::Aabb<Real> box = geometry.bounds();
    CHECK(double(box.min.x) <= -1);
    CHECK(double(box.max.x) >= 11);
    for (double time : {0.0, 0.5, 1.0}) {
        CAPTURE(time);
        const double x = 10 * time;
        prism::Ray<Real> at_object{prism::Vec3<Real>(Real(x), 0, 5), prism::Vec3<Real>(0, 0, -1), Real(0),
                                   prism::infinity<Real>, Real(time)};
        prism::Hit<Real> hit;
        REQUIRE(prism::closest_hit(geometry, at_object, hit));
        CHECK(double(hit.t) == doctest::Approx(4));
        // The surface point's object-space position is where the unmoved sphere was hit.
        const prism::SurfacePoint<Real> point = geometry.surface(at_object, hit);
        CHECK(double(point.local_position.z) == doctest::Approx(1));
        CHECK(double(point.local_position.x) == doctest::Approx(0).scale(1e-5));
        // Where the sphere was at another instant, the ray passes through empty space.
        prism::Ray<Real> elsewhere = at_object;
        elsewhere.time = Real(time < 0.5 ? 1.0 : 0.0);
        CHECK_FALSE(prism::blocked(geometry, elsewhere));
    }
}

TEST_CASE_TEMPLATE("perturb: zero roughness keeps the direction, roughness tilts it within the course's square", Real,
                   float, double) {
    const prism::Vec3<Real> mirror = glm::normalize(prism::Vec3<Real>(1, 2, -0.5));
    const prism::Vec3<Real> same = prism::perturb(mirror, Real(0), prism::Vec2<Real>(Real(0.9), Real(0.1)));
    for (int axis = 0; axis < 3; ++axis) CHECK(double(same[axis]) == doctest::Approx(double(mirror[axis])));
    prism::Random random(3);
    double largest = 0;
    for (int i = 0; i < 1000; ++i) {
        const prism::Vec3<Real> tilted = prism::perturb(mirror, Real(0.2), random.uniform2<Real>());
        CHECK(double(glm::length(tilted)) == doctest::Approx(1).epsilon(1e-6));
        largest = std::max(largest, std::acos(std::min(1.0, double(glm::dot(tilted, mirror)))));
    }
    // The offset a u + b v has length at most 0.2 * sqrt(2) / 2: tan of the angle is at most it.
    CHECK(largest <= std::atan(0.2 * std::sqrt(0.5)) + 1e-4);
    CHECK(largest > 0.05);
}

TEST_CASE_TEMPLATE("Renderer: multisampled, lens, area-lit, glossy and moving images are identical at 1 and 2 threads",
                   Real, float, double) {
    scene::Scene world;
    scene::Camera camera = looking_down_z(24, 16);
    camera.num_samples = 9;
    camera.aperture_size = 0.2;
    camera.focus_distance = 8;
    camera.filter = scene::PixelFilter::gaussian;
    world.cameras.push_back(camera);
    world.materials.push_back(matte(0.7));
    scene::Material glossy;
    glossy.type = scene::MaterialType::mirror;
    glossy.mirror = {0.8, 0.8, 0.8};
    glossy.diffuse = {0.1, 0.1, 0.1};
    glossy.roughness = 0.3;
    world.materials.push_back(glossy);
    world.planes.push_back({"floor", 0, {0, -1, 0}, {0, 1, 0}, glm::dmat4(1.0)});
    scene::Sphere ball{"ball", 1, {0, 0, 0}, 1, glm::dmat4(1.0)};
    ball.motion = {0.5, 0, 0};
    world.spheres.push_back(ball);
    world.area_lights.push_back({"panel", {-1, 4, -1}, {2, 0, 0}, {0, 0, 2}, {20, 20, 20}});
    // The run-time sampler choice (ChosenPattern), as the shipped renderers take it: one type for
    // every sampler kind below, and the same type test_object_lights renders (one unity group).
    using Complete = prism::Config<Real, prism::Bvh<prism::Watertight>, prism::AllLightSet, prism::all_features,
                                   prism::Whitted, prism::ChosenPattern>;
    const prism::Renderer<Complete> renderer(world);
    const auto render_with_threads = [&](std::size_t threads) {
        tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, threads);
        return renderer.render(world.cameras[0]);
    };
    const prism::Image one = render_with_threads(1);
    const prism::Image two = render_with_threads(2);
    REQUIRE(one.pixels.size() == two.pixels.size());
    CHECK(one.pixels == two.pixels);
    // And the image is not black: the area light does light the scene.
    float brightest = 0;
    for (const auto& pixel : one.pixels) brightest = std::max(brightest, pixel.r);
    CHECK(brightest > 0.1f);
    // Another seed gives another image (the streams are really used).
    const prism::Renderer<Complete> reseeded(world, prism::RendererSettings{prism::BackfaceCulling::triangles, prism::RayOffset::scene_epsilon, 99});
    CHECK(reseeded.render(world.cameras[0]).pixels != one.pixels);
}

TEST_CASE_TEMPLATE("Renderer: a pixel is its camera samples' filter-weighted mean, in their order, bit for bit", Real,
                   float, double) {
    // Point lights and matte surfaces draw nothing after the camera samples, so radiance() (which
    // starts from pixel (0, 0)'s first sample) gives each sample's radiance along its ray. A thin
    // lens makes every ray depend on its lens point and the Gaussian filter weighs it. One sample
    // (Renderer::one_sample_row: the centre, weight 1 without the filter) and 4 (a jittered grid
    // for the stream) and 5 (n-rooks: Renderer::pixel, every sample's ray and weight made before
    // the traces) must each add w_i L_i in the samples' order and divide by the sum of the
    // weights. The camera samples are the stream's (IndependentPattern: camera_samples, drawn
    // first from the pixel's stream) or, for the default sampler (ZSobol), each sample's own
    // camera dimensions (camera_sample).
    const auto check = [&]<class Pattern>(int count) {
        CAPTURE(count);
        scene::Scene world;
        scene::Camera camera = looking_down_z(24, 16);
        camera.num_samples = count;
        camera.aperture_size = 0.3;
        camera.focus_distance = 7;
        camera.filter = scene::PixelFilter::gaussian;
        world.cameras.push_back(camera);
        world.materials.push_back(matte(0.7));
        world.planes.push_back({"floor", 0, {0, -1, 0}, {0, 1, 0}, glm::dmat4(1.0)});
        world.spheres.push_back({"ball", 0, {0.3, 0, 0}, 1, glm::dmat4(1.0)});
        world.point_lights.push_back({"bulb", {2, 5, 3}, {40, 40, 40}});
        using Punctual = prism::Config<Real, prism::Bvh<prism::Watertight>, prism::PointLightSet, prism::Features{},
                                       prism::Whitted, Pattern>;
        const prism::Renderer<Punctual> renderer(world);
        const prism::Image image = renderer.render(world.cameras[0]);
        const prism::ThinLensCamera<Real> lens(camera, camera.width, camera.height);
        const Pattern pattern = prism::make_pattern<Pattern>({count, camera.width, camera.height, 0, {}});
        std::vector<prism::CameraSample<Real>> samples;
        std::vector<prism::Vec2<Real>> scratch;
        int mismatches = 0, lit = 0;
        for (int y = 0; y < camera.height; ++y)
            for (int x = 0; x < camera.width; ++x) {
                if constexpr (std::is_same_v<Pattern, prism::IndependentPattern>) {
                    prism::Random random = prism::Random::for_pixel(x, y, 0);
                    prism::camera_samples(count, random, samples, scratch);
                } else {
                    auto sampler = pattern.for_pixel(x, y);
                    samples.clear();
                    for (int i = 0; i < count; ++i) {
                        sampler.start_sample(i);
                        samples.push_back(prism::camera_sample<Real>(sampler, count == 1, {true, false}));
                    }
                }
                prism::Vec3<Real> sum(0);
                Real weights = 0;
                for (const prism::CameraSample<Real>& sample : samples) {
                    const prism::Ray<Real> ray =
                        lens.ray(Real(x) + sample.pixel.x, Real(y) + sample.pixel.y, sample.lens, sample.time);
                    const Real weight = prism::filter_weight(camera.filter, sample.pixel);
                    sum += weight * renderer.radiance(ray);
                    weights += weight;
                }
                const glm::vec3 expected(sum / weights);
                mismatches += std::memcmp(&expected, &image(x, y), sizeof expected) != 0;
                lit += expected.r > 0.0f;
            }
        CHECK(mismatches == 0);
        CHECK(lit > 50);  // the light reaches the ball and the floor
    };
    static_assert(std::is_same_v<prism::DefaultPattern, prism::ZSobolPattern>, "the second case is the default's");
    for (const int count : {1, 4, 5}) {
        check.template operator()<prism::IndependentPattern>(count);
        check.template operator()<prism::DefaultPattern>(count);
    }
}

TEST_CASE_TEMPLATE("Renderer: a row's mirrors and conductors, their reflections traced side by side, give each pixel's radiance bit for bit",
                   Real, float, double) {
    // A scene the geometry tests side by side (a top level of spheres, a floor of two world-space
    // triangles): one_sample_row's rows, radiance_row's shadow rays and its deferred reflections
    // (intersect_each at depth 1, then shade). Point lights, mirrors and conductors without
    // roughness draw nothing, so radiance() along each pixel's centre ray (the recursive trace,
    // a ray at a time) must give every pixel's bits. Rows of both materials, reflections that
    // meet a sphere, the floor or nothing, and chains of them to MaxRecursionDepth.
    scene::Scene world;
    scene::Camera camera = looking_down_z(40, 28);
    camera.position = {0, 1.5, 10};
    world.cameras.push_back(camera);
    scene::Material mirror = matte(0.2);
    mirror.type = scene::MaterialType::mirror;
    mirror.mirror = glm::dvec3(0.5, 0.6, 0.7);
    mirror.specular = glm::dvec3(0.4);
    mirror.phong_exponent = 20;
    scene::Material conductor = matte(0.1);
    conductor.type = scene::MaterialType::conductor;
    conductor.mirror = glm::dvec3(0.9, 0.8, 0.6);
    conductor.refraction_index = 0.37;
    conductor.absorption_index = 2.8;
    world.materials = {mirror, conductor, matte(0.7)};
    world.spheres.push_back({"mirror ball", 0, {-1.2, 0, 0}, 1, glm::dmat4(1.0)});
    world.spheres.push_back({"copper ball", 1, {1.3, 0.2, -0.5}, 1.1, glm::dmat4(1.0)});
    world.spheres.push_back({"matte ball", 2, {0, 2.2, -2}, 0.6, glm::dmat4(1.0)});
    world.planes.push_back({"wall", 2, {0, 0, -6}, {0, 0, 1}, glm::dmat4(1.0)});  // what the floor mirrors
    scene::Mesh floor;
    floor.material = 0;
    floor.positions = {{-8, -1, -8}, {8, -1, -8}, {8, -1, 8}, {-8, -1, 8}};
    floor.triangles = {{0, 2, 1}, {0, 3, 2}};
    world.meshes.push_back(floor);
    world.point_lights.push_back({"key", {3, 6, 4}, {60, 60, 60}});
    world.point_lights.push_back({"fill", {-4, 3, 2}, {15, 12, 10}});
    world.ambient_light = glm::dvec3(0.05);
    using Punctual = prism::Config<Real, prism::WideBvh<prism::Watertight, 8>, prism::PointLightSet>;
    // Indexed: a transformed mesh of 72 triangles joins the top level, which then keeps its
    // index (SceneGeometry::occluded_through_index's rows of shadow rays, intersect one ray at
    // a time); it stands behind the balls, where the floor and the copper ball reflect it.
    const scene::Mesh tent = ridged_tent(2);
    for (const bool indexed : {false, true}) {
        CAPTURE(indexed);
        if (indexed) world.meshes.push_back(tent);
        REQUIRE((prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>>(world).route() == prism::BatchRoute::leaf_lanes) ==
                !indexed);
        world.max_recursion_depth = 0;
        const prism::Image unreflected = prism::Renderer<Punctual>(world).render(world.cameras[0]);
        std::optional<prism::Image> once;
        for (const int depth : {1, 4, 10}) {  // 10: past the rows' depth, the last bounces one by one
            CAPTURE(depth);
            world.max_recursion_depth = depth;
            const prism::Renderer<Punctual> renderer(world);
            const prism::Image image = renderer.render(world.cameras[0]);
            const prism::ThinLensCamera<Real> lens(camera, camera.width, camera.height);
            int mismatches = 0, reflecting = 0, chained = 0;
            for (int y = 0; y < camera.height; ++y)
                for (int x = 0; x < camera.width; ++x) {
                    prism::Random random = prism::Random::for_pixel(x, y, 0);
                    const prism::CameraSample<Real> sample = prism::centre_sample<Real>(random);
                    const prism::Ray<Real> ray =
                        lens.ray(Real(x) + sample.pixel.x, Real(y) + sample.pixel.y, sample.lens, sample.time);
                    const glm::vec3 expected(prism::Vec3<Real>(0) + renderer.radiance(ray));
                    mismatches += std::memcmp(&expected, &image(x, y), sizeof expected) != 0;
                    reflecting += image(x, y) != unreflected(x, y);  // a reflection brought something back
                    if (once) chained += image(x, y) != (*once)(x, y);  // and a reflection of a reflection
                }
            CHECK(mismatches == 0);
            // Measured: 384 pixels at depth 1 and 408 at depth 4 (of 1120), 68 changed by the
            // deeper bounces; the bounds say the scene exercises what the test is for.
            CHECK(reflecting > 300);
            if (depth == 4) CHECK(chained > 30);
            once = image;
        }
    }
}

TEST_CASE_TEMPLATE("Renderer: a pixel's samples lit side by side (radiances_at) give the one-by-one trace's bits",
                   Real, float, double) {
    // Renderer::pixel hands a multi-sample pixel's camera hits to WhittedIntegrator::radiances_at,
    // which makes the shadow rays to the lights that draw nothing (point, directional, spot) for
    // every sample first and tests them side by side, then shades each sample in its turn from
    // the pixel's one stream. The reference is the integrator's own recursive trace (radiance),
    // sample after sample on that stream, summed with the filter weights as Renderer::pixel sums
    // them: every draw (the area light's, the rough mirror's, the lens's) must fall where it
    // fell, and every pixel's bits must agree. Textures (a checkerboard's replace_kd, an image's
    // replace_all, which shades nothing), glass, a rough mirror and a conductor; 5, 16 and 40
    // samples (radiances_at's chunks of 16, Renderer::pixel's batches of 32); both ray offsets;
    // without and with an index (a transformed mesh joins the top level).
    scene::Scene world;
    scene::Camera camera = looking_down_z(14, 10);
    camera.position = {0, 1.5, 10};
    camera.aperture_size = 0.15;
    camera.focus_distance = 9;
    camera.filter = scene::PixelFilter::gaussian;
    world.cameras.push_back(camera);
    scene::Material floor_material = matte(0.6);
    floor_material.specular = glm::dvec3(0.3);
    floor_material.phong_exponent = 12;
    scene::Material glass;
    glass.type = scene::MaterialType::dielectric;
    glass.refraction_index = 1.5;
    glass.absorption_coefficient = glm::dvec3(0.2, 0.05, 0.1);
    scene::Material rough_mirror = matte(0.1);
    rough_mirror.type = scene::MaterialType::mirror;
    rough_mirror.mirror = glm::dvec3(0.7);
    rough_mirror.roughness = 0.2;
    scene::Material conductor = matte(0.1);
    conductor.type = scene::MaterialType::conductor;
    conductor.mirror = glm::dvec3(0.9, 0.8, 0.6);
    conductor.refraction_index = 0.37;
    conductor.absorption_index = 2.8;
    world.materials = {floor_material, glass, rough_mirror, conductor, matte(0.5)};
    scene::Texture checker;
    checker.kind = scene::TextureKind::checkerboard;
    checker.decal_mode = scene::DecalMode::replace_kd;
    checker.scale = 1.3;
    checker.black_color = glm::dvec3(0.1, 0.2, 0.1);
    checker.white_color = glm::dvec3(0.9, 0.8, 0.7);
    world.textures.push_back(checker);
    prism::Image stripes(4, 4);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) stripes(x, y) = glm::vec3(float(x) / 4, 0.5f, float(y) / 4);
    world.images.push_back({"in-code", std::make_shared<const prism::Texels>(std::move(stripes)), false});
    scene::Texture painted;
    painted.kind = scene::TextureKind::image;
    painted.decal_mode = scene::DecalMode::replace_all;
    painted.normalizer = 1;
    world.textures.push_back(painted);
    scene::Mesh floor;
    floor.material = 0;
    floor.positions = {{-8, -1, -8}, {8, -1, -8}, {8, -1, 8}, {-8, -1, 8}};
    floor.triangles = {{0, 2, 1}, {0, 3, 2}};
    floor.textures = {0};
    world.meshes.push_back(floor);
    world.spheres.push_back({"glass ball", 1, {-1.3, 0, 0.5}, 1, glm::dmat4(1.0)});
    world.spheres.push_back({"rough ball", 2, {1.2, 0.1, -0.6}, 1.1, glm::dmat4(1.0)});
    world.spheres.push_back({"copper ball", 3, {0.2, 2.1, -2}, 0.6, glm::dmat4(1.0)});
    scene::Sphere painted_ball{"painted ball", 4, {-2.6, 1.8, -1.5}, 0.5, glm::dmat4(1.0)};
    painted_ball.textures = {1};
    world.spheres.push_back(painted_ball);
    world.planes.push_back({"wall", 4, {0, 0, -6}, {0, 0, 1}, glm::dmat4(1.0)});
    world.point_lights.push_back({"key", {3, 6, 4}, {60, 60, 60}});
    world.point_lights.push_back({"fill", {-4, 3, 2}, {15, 12, 10}});
    world.directional_lights.push_back({"sun", {0.3, -1, -0.4}, {0.4, 0.4, 0.35}});
    world.spot_lights.push_back({"spot", {0, 5, 1}, {0, -1, -0.2}, {80, 70, 60}, 50, 30});
    world.area_lights.push_back({"panel", {-1, 4.5, -1}, {2, 0, 0}, {0, 0, 2}, {6, 6, 6}});
    world.ambient_light = glm::dvec3(0.05);
    world.max_recursion_depth = 4;
    const scene::Mesh tent = ridged_tent(4);  // behind the balls: the scene keeps its index
    // The run-time sampler choice (ChosenPattern), as the shipped renderers take it: one type for
    // every sampler kind below, and the same type test_object_lights renders (one unity group).
    using Complete = prism::Config<Real, prism::Bvh<prism::Watertight>, prism::AllLightSet, prism::all_features,
                                   prism::Whitted, prism::ChosenPattern>;
    using Whole = prism::Renderer<Complete>;
    for (const bool indexed : {false, true}) {
        CAPTURE(indexed);
        if (indexed) world.meshes.push_back(tent);
        for (const prism::RayOffset offset : {prism::RayOffset::scene_epsilon, prism::RayOffset::error_bound}) {
            CAPTURE(int(offset));
            // (Named, not bound: clang 14's CAPTURE cannot capture a structured binding.)
            for (const std::pair<int, prism::SamplerKind>& run : {std::pair{5, prism::SamplerKind::independent},
                                                                  std::pair{16, prism::SamplerKind::independent},
                                                                  std::pair{40, prism::SamplerKind::independent},
                                                                  std::pair{16, prism::SamplerKind::stratified},
                                                                  std::pair{40, prism::SamplerKind::sobol}}) {
                const int count = run.first;
                const prism::SamplerKind kind = run.second;
                CAPTURE(count);
                CAPTURE(prism::sampler_name(kind));
                world.cameras[0].num_samples = count;
                const prism::RendererSettings settings{prism::BackfaceCulling::triangles, offset, 7, kind};
                const Whole renderer(world, settings);
                const prism::Image image = renderer.render(world.cameras[0]);
                const prism_test::RendererParts<Whole> parts(world, settings);
                const auto& integrator = parts.integrator;
                REQUIRE(integrator.prelights());
                const prism::ThinLensCamera<Real> lens(world.cameras[0], camera.width, camera.height);
                const auto pattern = prism::make_pattern<typename Whole::Pattern>(
                    {count, camera.width, camera.height, settings.seed, settings.sampler});
                int mismatches = 0, distinct = 0;
                std::set<std::array<float, 3>> colours;
                for (int y = 0; y < camera.height; ++y)
                    for (int x = 0; x < camera.width; ++x) {
                        const glm::vec3 expected = prism_test::one_by_one_pixel(
                            integrator, lens, world.cameras[0], pattern, count, x, y, settings.seed,
                            [](auto& sampler, const prism::Vec2<Real>& pixel_uv, Real spread) {
                                return typename Whole::Integrator::CameraPath{sampler, pixel_uv, spread};
                            });
                        mismatches += std::memcmp(&expected, &image(x, y), sizeof expected) != 0;
                        colours.insert({expected.r, expected.g, expected.b});
                    }
                distinct = int(colours.size());
                CHECK(mismatches == 0);
                CHECK(distinct > 100);  // of 140 pixels: the scene's variety reaches the image
            }
        }
    }
}

TEST_CASE_TEMPLATE("Whitted: seven point lights add up, in their order, as each alone gives it, bit for bit", Real,
                   float, double) {
    // A guard for any reordering of the light loop (whole9 measured batching the lights' shadow
    // rays; not kept). Without ambient light, emission or
    // recursion a point's radiance is 0 + the sum of the lights' terms in the scene's order, and a
    // renderer with one light alone gives that light's term (point lights and matte or Phong
    // surfaces draw nothing), so the sum of the seven one-light renders, added in order, must be
    // the seven-light render's value. Two lights are below the floor (no term), one is hidden
    // from part of the floor by the ball.
    scene::Scene world;
    scene::Camera camera = looking_down_z(16, 12);
    world.cameras.push_back(camera);
    scene::Material phong = matte(0.6);
    phong.specular = glm::dvec3(0.3);
    phong.phong_exponent = 12;
    world.materials.push_back(phong);
    world.planes.push_back({"floor", 0, {0, -1, 0}, {0, 1, 0}, glm::dmat4(1.0)});
    world.spheres.push_back({"ball", 0, {0.3, 0, 0}, 1, glm::dmat4(1.0)});
    const std::vector<scene::PointLight> bulbs = {
        {"a", {2, 5, 3}, {40, 40, 40}},    {"b", {-3, 4, 1}, {25, 10, 5}}, {"c", {0, -3, 0}, {50, 50, 50}},
        {"d", {0.3, 3, 0}, {30, 30, 30}},  {"e", {4, 1, -2}, {8, 20, 8}},  {"f", {1, -2, 2}, {9, 9, 9}},
        {"g", {-1, 6, -4}, {60, 40, 20}}};
    world.point_lights = bulbs;
    using Punctual = prism::Config<Real, prism::Bvh<prism::Watertight>, prism::PointLightSet>;
    const prism::Renderer<Punctual> all(world);
    std::vector<std::unique_ptr<prism::Renderer<Punctual>>> alone;
    for (const scene::PointLight& bulb : bulbs) {
        scene::Scene one = world;
        one.point_lights = {bulb};
        alone.push_back(std::make_unique<prism::Renderer<Punctual>>(one));
    }
    const prism::ThinLensCamera<Real> lens(camera, camera.width, camera.height);
    int mismatches = 0, lit = 0;
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
            const prism::Ray<Real> ray = lens.ray(Real(x) + Real(0.5), Real(y) + Real(0.5), prism::Vec2<Real>(Real(0.5)), 0);
            prism::Vec3<Real> expected(0);
            for (const auto& renderer : alone) expected += renderer->radiance(ray);
            const prism::Vec3<Real> got = all.radiance(ray);
            mismatches += std::memcmp(&expected, &got, sizeof expected) != 0;
            lit += got.r > 0;
        }
    CHECK(mismatches == 0);
    CHECK(lit > 60);  // the floor and the ball
}

TEST_CASE("render_scene: a fitted renderer refuses what it was compiled without") {
    scene::Scene world;
    world.cameras.push_back(looking_down_z(2, 2));
    world.materials.push_back(matte(0.5));
    scene::Sphere ball{"ball", 0, {0, 0, 0}, 1, glm::dmat4(1.0)};
    ball.motion = {1, 0, 0};
    world.spheres.push_back(ball);
    using Fitted = prism::Config<float, prism::Bvh<prism::Watertight>, prism::PointLightSet>;
    const auto build_fitted = [&] { const prism::Renderer<Fitted> fitted(world); };
    CHECK_THROWS_WITH_AS(build_fitted(), doctest::Contains("MotionBlur"), std::invalid_argument);
    // render_scene picks the complete renderer for it, and says why.
    std::ostringstream log;
    const auto images = prism::render_scene(world, prism::RenderOptions{}, log);
    CHECK(images.size() == 1);
    CHECK(log.str().find("motion blur") != std::string::npos);
}

TEST_CASE_TEMPLATE("Random::skip: the stream after skipping n draws is the stream after making them", Real, float,
                   double) {
    for (int n : {0, 1, 2, 5, 37}) {
        CAPTURE(n);
        prism::Random drawn = prism::Random::for_pixel(11, 2, 7), skipped = drawn;
        for (int i = 0; i < n; ++i) (void)drawn.uniform<Real>();
        skipped.skip<Real>(n);
        for (int i = 0; i < 8; ++i) REQUIRE(skipped.uniform<Real>() == drawn.uniform<Real>());
    }
    // Skipping is not a no-op: the next draw after a skip differs from the unskipped one.
    prism::Random a = prism::Random::for_pixel(1, 1, 0), b = a;
    b.skip<Real>(1);
    CHECK(a.uniform<Real>() != b.uniform<Real>());
}

TEST_CASE_TEMPLATE("Random::for_row and centre_rays: a pinhole row's streams and rays, lane by lane, as pixel by pixel",
                   Real, float, double) {
    // one_sample_row's pinhole path: for_row's streams past the lens draws, the time drawn
    // from each, and ThinLensCamera::centre_rays, against for_pixel, centre_sample and ray at
    // every pixel centre of rows anywhere in the image (a row of 16 lanes that runs past its
    // right edge included), for two seeds. The camera is read at run time, as from a file: with
    // its frame known at compile time GCC 12 folds ray()'s sums into a vfmaddsub, fused
    // whatever -ffp-contract says (seen here in double), and the reference is no longer ray().
    volatile double tilt = 0.3;
    scene::Camera camera = looking_down_z(37, 9);
    camera.gaze = glm::normalize(glm::dvec3(tilt, -0.2, -1));
    camera.up = {0.1, 1, 0};
    const prism::ThinLensCamera<Real> lens(camera, camera.width, camera.height);
    REQUIRE(!lens.has_aperture());
    for (const std::uint64_t seed : {std::uint64_t(0), std::uint64_t(977)})
        for (int y = 0; y < camera.height; ++y)
            for (int x0 = 0; x0 < camera.width; x0 += 16) {
                std::array<prism::Random, 16> streams;
                std::array<Real, 16> times;
                prism::Random::for_row<Real>(x0, y, seed, 2, streams, times);
                std::array<prism::Ray<Real>, 16> rays;
                lens.centre_rays(x0, y, times, rays);
                for (int i = 0; i < 16; ++i) {
                    CAPTURE(x0 + i);
                    prism::Random random = prism::Random::for_pixel(x0 + i, y, seed);
                    const prism::CameraSample<Real> sample = prism::centre_sample<Real>(random);
                    const prism::Ray<Real> ray =
                        lens.ray(Real(x0 + i) + sample.pixel.x, Real(y) + sample.pixel.y, sample.lens, sample.time);
                    const prism::Ray<Real>& row = rays[std::size_t(i)];
                    REQUIRE(std::memcmp(&row.origin, &ray.origin, sizeof ray.origin) == 0);
                    CAPTURE(y);
                    REQUIRE(std::memcmp(&row.direction, &ray.direction, sizeof ray.direction) == 0);
                    REQUIRE(std::memcmp(&row.time, &ray.time, sizeof ray.time) == 0);
                    REQUIRE(row.t_min == ray.t_min);
                    REQUIRE(row.t_max == ray.t_max);
                    // The streams go on alike.
                    for (int k = 0; k < 3; ++k) REQUIRE(streams[std::size_t(i)].template uniform<Real>() == random.uniform<Real>());
                }
            }
}

TEST_CASE_TEMPLATE("SceneGeometry::surface: without (u, v) and tangents, without the spawn point, the rest the same",
                   Real, float, double) {
    scene::Scene world;
    world.materials.push_back(matte(0.5));
    world.spheres.push_back({"plain", 0, {0, 0, 0}, 1, glm::dmat4(1.0)});
    // Placed by a transformation: scaled and moved, so the object-space fields differ from world's.
    world.spheres.push_back({"placed", 0, {0, 0, 0}, 1,
                             glm::scale(glm::translate(glm::dmat4(1.0), glm::dvec3(5, 0, 0)), glm::dvec3(1, 2, 1))});
    scene::Mesh mesh;
    mesh.positions = {{9, -1, 0}, {11, -1, 0}, {10, 1, 0}};
    mesh.uvs = {{0, 0}, {1, 0}, {0, 1}};
    mesh.triangles = {{0, 1, 2}};
    world.meshes.push_back(mesh);
    world.planes.push_back({"floor", 0, {0, -5, 0}, {0, 1, 0}});
    const prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight>> geometry(world);
    const std::vector<prism::Ray<Real>> rays{
        {prism::Vec3<Real>(Real(0.3), Real(0.4), 9), prism::Vec3<Real>(0, 0, -1)},
        {prism::Vec3<Real>(Real(5.2), Real(0.4), 9), prism::Vec3<Real>(0, 0, -1)},
        {prism::Vec3<Real>(Real(10.1), Real(0.2), 9), prism::Vec3<Real>(0, 0, -1)},
        {prism::Vec3<Real>(Real(20), 0, 0), prism::Vec3<Real>(0, -1, 0)}};
    for (std::size_t r = 0; r < rays.size(); ++r) {
        CAPTURE(r);
        prism::Ray<Real> ray = rays[r];
        prism::Hit<Real> hit;
        REQUIRE(prism::closest_hit(geometry, ray, hit));
        const prism::SurfacePoint<Real> full = geometry.surface(ray, hit);
        const prism::SurfacePoint<Real> bare = geometry.template surface<false>(ray, hit);
        const prism::SurfacePoint<Real> unspawned = geometry.surface(ray, hit, false);
        CHECK(full.object_error != prism::Vec3<Real>(0));
        CHECK(unspawned.object_point == prism::Vec3<Real>(0));
        CHECK(unspawned.object_error == prism::Vec3<Real>(0));
        CHECK(unspawned.uv == full.uv);
        CHECK(unspawned.dpdu == full.dpdu);
        CHECK(unspawned.dpdv == full.dpdv);
        if (r < 2) {  // the spheres: (u, v) and tangents only when parametrised
            CHECK(full.uv != prism::Vec2<Real>(0));
            CHECK(full.dpdu != prism::Vec3<Real>(0));
            CHECK(bare.uv == prism::Vec2<Real>(0));
            CHECK(bare.dpdu == prism::Vec3<Real>(0));
            CHECK(bare.dpdv == prism::Vec3<Real>(0));
        } else {  // a mesh fills its own, planes have none
            CHECK(bare.uv == full.uv);
            CHECK(bare.dpdu == full.dpdu);
        }
        CHECK(bare.object_point == full.object_point);
        CHECK(bare.object_error == full.object_error);
        for (const prism::SurfacePoint<Real>* point : {&bare, &unspawned}) {
            CHECK(point->position == full.position);
            CHECK(point->geometric_normal == full.geometric_normal);
            CHECK(point->shading_normal == full.shading_normal);
            CHECK(point->local_position == full.local_position);
            CHECK(point->object_normal == full.object_normal);
            CHECK(point->texture_position == full.texture_position);
            CHECK(point->material == full.material);
            CHECK(point->object == full.object);
        }
    }
}
