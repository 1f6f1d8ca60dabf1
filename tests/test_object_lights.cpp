// Object lights (LightMesh, LightSphere): their densities against area and solid angle, their
// estimates against known irradiance, the loader in XML and JSON, the renderer's view of their
// radiance, and the refusal of a renderer prism does not implement.
#include "temporary_folder.hpp"

#include <prism/io/load.hpp>
#include <prism/light/area_light.hpp>
#include <prism/light/light_mesh.hpp>
#include <prism/light/light_sphere.hpp>
#include <prism/render/render_scene.hpp>
#include <prism/sampling/random.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <string>

namespace {

namespace scene = prism::scene;
using prism_test::TemporaryFolder;

constexpr double pi = 3.14159265358979323846;

}  // namespace

TEST_CASE_TEMPLATE("LightMesh: triangles chosen by area, solid-angle density |x - q|^2 / (A |cos|)", Real, float,
                   double) {
    scene::Mesh mesh;
    // Two triangles of areas 0.5 and 1.5 (the second three times the first), in the plane y = 2.
    mesh.positions = {{0, 2, 0}, {1, 2, 0}, {0, 2, 1}, {4, 2, 0}};
    mesh.triangles = {{0, 1, 2}, {1, 3, 2}};
    mesh.radiance = {3, 2, 1};
    const auto light = prism::LightMesh<Real>::make(mesh, glm::dmat4(1.0), 0);
    CHECK(double(light.area) == doctest::Approx(2.0));
    prism::Random random(7);
    const prism::ShadingFrame<Real> at{prism::Vec3<Real>(0.5, 0, 0.25), prism::Vec3<Real>(0, 1, 0)};
    int in_first = 0;
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
        const prism::LightSample<Real> sample = light.sample(at, random.uniform2<Real>());
        const prism::Vec3<Real> point = at.position + sample.direction * sample.distance;
        CHECK(double(point.y) == doctest::Approx(2.0).epsilon(1e-5));
        in_first += (point.x + point.z <= 1) ? 1 : 0;
        // The density from area to solid angle, written out again.
        const double cos_light = std::abs(double(sample.direction.y));
        const double expected = double(sample.distance) * double(sample.distance) / (2.0 * cos_light);
        CHECK(double(sample.pdf) == doctest::Approx(expected).epsilon(1e-4));
        CHECK(double(light.pdf(at.position, point, prism::Vec3<Real>(0, 1, 0))) == doctest::Approx(expected).epsilon(1e-4));
        CHECK(double(sample.radiance.r) == doctest::Approx(3.0 / expected).epsilon(1e-4));
    }
    // Binomial: 0.25 n = 5000 with a standard deviation of 61; 4 sigma.
    CHECK(std::abs(in_first - n / 4) < 250);
}

TEST_CASE_TEMPLATE("LightMesh: its irradiance estimate matches the area light of the same rectangle", Real, float,
                   double) {
    // A 1 x 1 square at y = 1 over a point at the origin facing up, as two triangles and as the
    // course's area light; both estimate the same irradiance (area_light is tested against it).
    scene::Mesh mesh;
    mesh.positions = {{-0.5, 1, -0.5}, {0.5, 1, -0.5}, {0.5, 1, 0.5}, {-0.5, 1, 0.5}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    mesh.radiance = {1, 1, 1};
    const auto light = prism::LightMesh<Real>::make(mesh, glm::dmat4(1.0), 0);
    // The irradiance of a unit square at distance 1 (centred above): 4 atan(1 / (2 sqrt(1.25))) / ...
    // integrated numerically here in double, on a 400 x 400 grid of the square.
    double exact = 0;
    const int grid = 400;
    for (int i = 0; i < grid; ++i)
        for (int j = 0; j < grid; ++j) {
            const double x = -0.5 + (i + 0.5) / grid, z = -0.5 + (j + 0.5) / grid;
            const double d2 = x * x + 1 + z * z;
            exact += (1.0 / d2) * (1.0 / d2) / (grid * grid);  // cos * cos / d^2 with cos = 1 / d
        }
    prism::Random random(11);
    double sum = 0;
    const int n = 200000;
    const prism::ShadingFrame<Real> at{prism::Vec3<Real>(0), prism::Vec3<Real>(0, 1, 0)};
    for (int i = 0; i < n; ++i) {
        const auto sample = light.sample(at, random.uniform2<Real>());
        sum += double(sample.radiance.g) * double(sample.direction.y);
    }
    CHECK(sum / n == doctest::Approx(exact).epsilon(0.005));
}

TEST_CASE_TEMPLATE("LightSphere: cone sampling gives the irradiance pi L (r / d)^2, every sample on the sphere", Real,
                   float, double) {
    for (const double distance : {3.0, 1000.0}) {
        CAPTURE(distance);
        const double radius = 0.5;
        const auto light =
            prism::LightSphere<Real>::make({0, distance, 0}, radius, glm::dmat4(1.0), {2, 2, 2}, 0);
        prism::Random random(3);
        double sum = 0;
        const int n = 20000;
        const prism::ShadingFrame<Real> at{prism::Vec3<Real>(0), prism::Vec3<Real>(0, 1, 0)};
        const double cone = 2 * pi * (1 - std::sqrt(1 - radius * radius / (distance * distance)));
        for (int i = 0; i < n; ++i) {
            const auto sample = light.sample(at, random.uniform2<Real>());
            const glm::dvec3 point = glm::dvec3(at.position + sample.direction * sample.distance);
            CHECK(glm::length(point - glm::dvec3(0, distance, 0)) == doctest::Approx(radius).epsilon(1e-3));
            // Uniform in the cone: the density is 1 / solid angle.
            CHECK(double(sample.pdf) == doctest::Approx(1 / cone).epsilon(distance > 10 ? 2e-3 : 1e-4));
            sum += double(sample.radiance.r) * double(sample.direction.y);
        }
        const double exact = pi * 2 * radius * radius / (distance * distance);
        CHECK(sum / n == doctest::Approx(exact).epsilon(0.01));
    }
}

TEST_CASE_TEMPLATE("LightSphere: an ellipsoid's densities integrate to its solid angle, and pdf() matches sample()",
                   Real, float, double) {
    // The course's ellipsoid light: a sphere of radius 0.2 scaled by (5, 1, 1), seen from 1.5 below.
    const glm::dmat4 transform = glm::translate(glm::dmat4(1.0), glm::dvec3(0.3, 1.5, 0.1)) *
                                 glm::scale(glm::dmat4(1.0), glm::dvec3(5, 1, 1));
    const auto light = prism::LightSphere<Real>::make({0, 0, 0}, 0.2, transform, {1, 1, 1}, 0);
    const prism::ShadingFrame<Real> at{prism::Vec3<Real>(0), prism::Vec3<Real>(0, 1, 0)};
    // E[1 / pdf] over the light's samples is the solid angle it subtends; measured apart by
    // counting uniform directions that hit the ellipsoid (in its object space, a unit sphere test).
    const glm::dmat4 inverse = glm::inverse(transform);
    prism::Random counting(5);
    int hits = 0;
    const int directions = 400000;
    for (int i = 0; i < directions; ++i) {
        const double z = 1 - 2 * counting.uniform<double>(), phi = 2 * pi * counting.uniform<double>();
        const double s = std::sqrt(std::max(0.0, 1 - z * z));
        const glm::dvec3 d(s * std::cos(phi), z, s * std::sin(phi));
        const glm::dvec3 o = glm::dvec3(inverse * glm::dvec4(0, 0, 0, 1));
        const glm::dvec3 v = glm::dmat3(inverse) * d;
        const double a = glm::dot(v, v), b = glm::dot(o, v), c = glm::dot(o, o) - 0.04;
        hits += (b * b - a * c >= 0 && -b > 0) ? 1 : 0;
    }
    const double solid_angle = 4 * pi * hits / directions;
    prism::Random random(9);
    double sum = 0;
    const int n = 100000;
    for (int i = 0; i < n; ++i) {
        const auto sample = light.sample(at, random.uniform2<Real>());
        REQUIRE(sample.pdf > 0);
        sum += 1 / double(sample.pdf);
        if (i % 100 == 0) {
            const prism::Vec3<Real> point = at.position + sample.direction * sample.distance;
            const prism::Vec3<Real> local = prism::Vec3<Real>(glm::inverse(light.to_world) * prism::Vec4<Real>(point, 1));
            const prism::Vec3<Real> normal = glm::normalize(light.normal_to_world * local);
            CHECK(double(light.pdf(at.position, point, normal)) == doctest::Approx(double(sample.pdf)).epsilon(2e-3));
        }
    }
    // The hit count's relative standard deviation is about 0.5%.
    CHECK(sum / n == doctest::Approx(solid_angle).epsilon(0.02));
}

namespace {

const char* const object_lights_xml = R"(<Scene>
    <Cameras><Camera id="1">
        <Position>0 0 0</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
        <NearPlane>-0.01 0.01 -0.01 0.01</NearPlane><NearDistance>1</NearDistance>
        <ImageResolution>1 1</ImageResolution><ImageName>out.exr</ImageName>
        <Renderer>PathTracing</Renderer>
        <RendererParams>NextEventEstimation ImportanceSampling RussianRoulette</RendererParams>
    </Camera></Cameras>
    <Materials><Material id="1"><DiffuseReflectance>0 0 0</DiffuseReflectance></Material></Materials>
    <Transformations><Translation id="1">0 0 -1</Translation></Transformations>
    <VertexData>-1 -1 -5 1 -1 -5 1 1 -5 -1 1 -5 0 0 -3</VertexData>
    <Objects>
        <LightMesh id="1"><Material>1</Material><Radiance>4 5 6</Radiance><Faces>1 2 3 1 3 4</Faces></LightMesh>
        <LightSphere id="2"><Material>1</Material><Center>5</Center><Radius>0.5</Radius>
            <Radiance>7 8 9</Radiance><Transformations>t1</Transformations></LightSphere>
    </Objects>
</Scene>)";

const char* const object_lights_json = R"({"Scene": {
    "Cameras": {"Camera": {"_id": "1", "Position": "0 0 0", "Gaze": "0 0 -1", "Up": "0 1 0",
        "NearPlane": "-0.01 0.01 -0.01 0.01", "NearDistance": "1", "ImageResolution": "1 1", "ImageName": "out.exr",
        "Renderer": "PathTracing", "RendererParams": "NextEventEstimation ImportanceSampling RussianRoulette"}},
    "Materials": {"Material": {"_id": "1", "DiffuseReflectance": "0 0 0"}},
    "Transformations": {"Translation": {"_data": "0 0 -1", "_id": "1"}},
    "VertexData": {"_data": "-1 -1 -5 1 -1 -5 1 1 -5 -1 1 -5 0 0 -3", "_type": "xyz"},
    "Objects": {
        "LightMesh": {"_id": "1", "Material": "1", "Radiance": "4 5 6", "Faces": {"_data": "1 2 3 1 3 4", "_type": "triangle"}},
        "LightSphere": {"_id": "2", "Material": "1", "Center": "5", "Radius": "0.5", "Radiance": "7 8 9",
                        "Transformations": "t1"}}
}})";

}  // namespace

TEST_CASE("loader: LightMesh, LightSphere, Renderer and RendererParams in XML and JSON") {
    TemporaryFolder folder;
    const scene::Scene from_xml = prism::io::load_scene(folder.write("objects.xml", object_lights_xml));
    const scene::Scene from_json = prism::io::load_scene(folder.write("objects.json", object_lights_json));
    for (const scene::Scene* world : {&from_xml, &from_json}) {
        CAPTURE(world->source);
        CHECK(world->unsupported.empty());
        REQUIRE(world->meshes.size() == 1);
        CHECK(world->meshes[0].radiance == glm::dvec3(4, 5, 6));
        CHECK(world->meshes[0].triangles.size() == 2);
        REQUIRE(world->spheres.size() == 1);
        CHECK(world->spheres[0].radiance == glm::dvec3(7, 8, 9));
        CHECK(world->spheres[0].transform != glm::dmat4(1.0));
        const scene::RendererParams& params = world->cameras.at(0).renderer;
        CHECK(params.path_tracing);
        CHECK(params.next_event_estimation);
        CHECK(params.importance_sampling);
        CHECK(params.russian_roulette);
        CHECK_FALSE(params.multiple_importance);
        const scene::Needs needs = scene::measure_needs(*world);
        CHECK(needs.path_tracing);
        CHECK(needs.lights == scene::bit(scene::LightKind::object));
    }
}

TEST_CASE("loader: a renderer prism does not implement is refused, naming the file and the element") {
    TemporaryFolder folder;
    std::string xml = object_lights_xml;
    const std::string from = "<Renderer>PathTracing</Renderer>";
    xml.replace(xml.find(from), from.size(), "<Renderer>ProgressivePhotonMapping</Renderer>");
    std::string message;
    try {
        prism::io::load_scene(folder.write("photons.xml", xml));
    } catch (const prism::io::LoadError& error) {
        message = error.what();
    }
    CAPTURE(message);
    CHECK(message.find("photons.xml") != std::string::npos);
    CHECK(message.find("<Renderer>") != std::string::npos);
    CHECK(message.find("ProgressivePhotonMapping") != std::string::npos);
    // An unknown path tracing parameter is refused too, not ignored.
    std::string typo = object_lights_xml;
    const std::string word = "RussianRoulette</RendererParams>";
    typo.replace(typo.find(word), word.size(), "RussianRulette</RendererParams>");
    CHECK_THROWS_AS(prism::io::load_scene(folder.write("typo.xml", typo)), prism::io::LoadError);
}

TEST_CASE_TEMPLATE("Renderer: rays see object lights' radiance, transformed and instanced, in both integrators", Real,
                   float, double) {
    TemporaryFolder folder;
    scene::Scene world = prism::io::load_scene(folder.write("objects.xml", object_lights_xml));
    // An instance of the LightMesh moved beside it, to the right.
    scene::MeshInstance instance;
    instance.base_mesh = 0;
    instance.transform = glm::translate(glm::dmat4(1.0), glm::dvec3(10, 0, 0));
    world.mesh_instances.push_back(instance);
    using Path = prism::Config<Real, prism::Bvh<prism::Watertight>, prism::AllLightSet, prism::all_features, prism::PathTracer>;
    const prism::Renderer<Path> renderer(world);
    // The sphere's centre moved to z = -4 by its Translation: a ray at it sees its radiance
    // (the Renderer's radiance() uses the ray tracer: cameras choose the path tracer).
    const auto along = [](double x, double y, double z) {
        return prism::Ray<Real>{prism::Vec3<Real>(0), prism::Vec3<Real>(glm::normalize(glm::dvec3(x, y, z)))};
    };
    CHECK(glm::dvec3(renderer.radiance(along(0, 0, -1))) == glm::dvec3(7, 8, 9));
    CHECK(glm::dvec3(renderer.radiance(along(0.8, 0.8, -5))) == glm::dvec3(4, 5, 6));
    CHECK(glm::dvec3(renderer.radiance(along(10, 0.5, -5))) == glm::dvec3(4, 5, 6));
    // The path-traced camera sees the sphere the same: black surfaces scatter nothing.
    const prism::Image image = renderer.render(world.cameras[0]);
    CHECK(double(image(0, 0).r) == doctest::Approx(7).epsilon(1e-5));
    // Light kinds: one mesh and its instance, one sphere.
    REQUIRE(renderer.lights().template of_type<prism::LightMesh>()->size() == 2);
    REQUIRE(renderer.lights().template of_type<prism::LightSphere>()->size() == 1);
}

namespace {

// A floor (y = 0, diffuse 1, no BRDF: the course's kd cos E) under one object light, seen by a
// ray-traced camera at y = 0.5 looking straight down through a tiny near plane: its one pixel
// is the floor's radiance at the origin, kd times the irradiance there.
scene::Scene floor_under(const scene::Mesh* light_mesh, const scene::Sphere* light_sphere) {
    scene::Scene world;
    scene::Material floor_material;
    floor_material.diffuse = {1, 1, 1};
    world.materials.push_back(floor_material);
    world.materials.push_back(scene::Material{});  // the light's: black
    scene::Mesh floor;
    floor.positions = {{-10, 0, -10}, {10, 0, -10}, {10, 0, 10}, {-10, 0, 10}};
    floor.triangles = {{0, 2, 1}, {0, 3, 2}};
    world.meshes.push_back(floor);
    if (light_mesh) world.meshes.push_back(*light_mesh);
    if (light_sphere) world.spheres.push_back(*light_sphere);
    scene::Camera camera;
    camera.position = {0, 0.5, 0};
    camera.gaze = {0, -1, 0};
    camera.up = {0, 0, 1};
    camera.near_distance = 1;
    camera.near_left = camera.near_bottom = -1e-4;
    camera.near_right = camera.near_top = 1e-4;
    camera.width = camera.height = 1;
    camera.num_samples = 4096;
    camera.image_name = "out.exr";
    world.cameras.push_back(camera);
    return world;
}

}  // namespace

TEST_CASE_TEMPLATE("ray tracer: object lights light the surfaces they face (their own surface does not shadow them)",
                   Real, float, double) {
    using Traced = prism::Config<Real, prism::Bvh<prism::Watertight>, prism::AllLightSet, prism::all_features,
                                 prism::Whitted, prism::ChosenPattern>;  // test_sampling's type
    SUBCASE("LightMesh: a unit square at y = 1, centred above the point") {
        scene::Mesh square;
        square.material = 1;
        square.positions = {{-0.5, 1, -0.5}, {0.5, 1, -0.5}, {0.5, 1, 0.5}, {-0.5, 1, 0.5}};
        square.triangles = {{0, 1, 2}, {0, 2, 3}};
        square.radiance = {2, 2, 2};
        const scene::Scene world = floor_under(&square, nullptr);
        // The irradiance of a parallel rectangle from its corner form factor (Howell's catalogue,
        // C-11): four 0.5 x 0.5 rectangles at height 1, E = pi L 4 F.
        const double x = 0.5, root = std::sqrt(1 + x * x);
        const double corner = (x / root * std::atan(x / root)) / pi;  // 2 (X/sqrt(1+X^2)) atan(..) / (2 pi)
        const double irradiance = pi * 2.0 * 4 * corner;
        const prism::Renderer<Traced> renderer(world);
        const prism::Image image = renderer.render(world.cameras[0]);
        CHECK(double(image(0, 0).g) == doctest::Approx(irradiance).epsilon(0.02));
    }
    SUBCASE("LightSphere: radius 0.25 at height 2, E = pi L (r / d)^2") {
        scene::Sphere sphere;
        sphere.material = 1;
        sphere.center = {0, 2, 0};
        sphere.radius = 0.25;
        sphere.radiance = {3, 3, 3};
        const scene::Scene world = floor_under(nullptr, &sphere);
        const prism::Renderer<Traced> renderer(world);
        const prism::Image image = renderer.render(world.cameras[0]);
        CHECK(double(image(0, 0).g) == doctest::Approx(pi * 3.0 * (0.25 / 2) * (0.25 / 2)).epsilon(0.02));
    }
}

TEST_CASE_TEMPLATE("path tracer: a mirror keeps its BRDF terms, as the ray tracer shades it", Real, float, double) {
    // The floor above, now a mirror (MirrorReflectance 0.5) with diffuse 1: the ray tracer gives
    // the diffuse term of the LightMesh's light plus the mirrored light (radiance 2 times 0.5);
    // the path tracer must estimate the same, with and without multiple importance sampling.
    using Path = prism::Config<Real, prism::Bvh<prism::Watertight>, prism::AllLightSet, prism::all_features,
                               prism::PathTracer>;
    scene::Mesh square;
    square.material = 1;
    square.positions = {{-0.5, 1, -0.5}, {0.5, 1, -0.5}, {0.5, 1, 0.5}, {-0.5, 1, 0.5}};
    square.triangles = {{0, 1, 2}, {0, 2, 3}};
    square.radiance = {2, 2, 2};
    scene::Scene world = floor_under(&square, nullptr);
    world.max_recursion_depth = 1;
    world.materials[0].type = scene::MaterialType::mirror;
    world.materials[0].mirror = {0.5, 0.5, 0.5};
    const prism::Renderer<Path> renderer(world);
    const double traced = double(renderer.render(world.cameras[0])(0, 0).g);
    const double x = 0.5, root = std::sqrt(1 + x * x);
    CHECK(traced == doctest::Approx(1.0 + pi * 2.0 * 4 * (x / root * std::atan(x / root)) / pi).epsilon(0.02));
    for (const bool mis : {false, true}) {
        CAPTURE(mis);
        scene::Camera camera = world.cameras[0];
        camera.renderer = {true, true, true, false, mis};
        CHECK(double(renderer.render(camera)(0, 0).g) == doctest::Approx(traced).epsilon(0.03));
    }
}
