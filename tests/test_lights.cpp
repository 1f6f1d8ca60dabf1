// Directional and spot lights: their samples against the course's formulas, the spot cone inside,
// across and outside with no ring at its edges, shadow rays to infinity through the renderer,
// the dispatcher's refusal to drop a light, and the loader reading the new elements (lights and
// Tonemap) from XML and JSON.
#include "temporary_folder.hpp"
#include "text_contains.hpp"

#include <prism/io/load.hpp>
#include <prism/light/directional_light.hpp>
#include <prism/light/spot_light.hpp>
#include <prism/render/render_scene.hpp>
#include <prism/render/renderer.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

using prism_test::contains;

namespace {

namespace fs = std::filesystem;
namespace scene = prism::scene;

constexpr double degrees = 3.14159265358979323846 / 180.0;

// A spot light at the origin shining down -y, coverage 60 and falloff 40 degrees (half angles 30
// and 20).
scene::SpotLight downward_spot(double coverage = 60, double falloff = 40) {
    scene::SpotLight light;
    light.position = {0, 0, 0};
    light.direction = {0, -2, 0};  // not unit: the light normalises it
    light.intensity = {400, 200, 100};
    light.coverage_angle = coverage;
    light.falloff_angle = falloff;
    return light;
}

// The point at distance `distance` from the spot, `angle_degrees` away from its axis.
template <class Real>
prism::Vec3<Real> point_at(double angle_degrees, double distance) {
    return prism::Vec3<Real>(glm::dvec3(std::sin(angle_degrees * degrees), -std::cos(angle_degrees * degrees), 0) * distance);
}

// The course's formula, written out again in double from the full angles.
double course_spot_factor(double alpha_degrees, double coverage, double falloff) {
    const double cos_alpha = std::cos(alpha_degrees * degrees);
    const double cos_coverage = std::cos(coverage / 2 * degrees), cos_falloff = std::cos(falloff / 2 * degrees);
    if (alpha_degrees <= falloff / 2) return 1;
    if (alpha_degrees >= coverage / 2) return 0;
    return std::pow((cos_alpha - cos_coverage) / (cos_falloff - cos_coverage), 4);
}

using prism_test::TemporaryFolder;

std::string load_error_of(const fs::path& file) {
    try {
        prism::io::load_scene(file);
    } catch (const prism::io::LoadError& error) {
        return error.what();
    }
    return "no error";
}

}  // namespace

TEST_CASE_TEMPLATE("DirectionalLight: towards the light, infinitely far, no falloff", Real, float, double) {
    scene::Scene world;
    world.directional_lights.push_back({"sun", {1, -0.8, -1}, {200, 150, 100}});
    const auto lights = prism::DirectionalLight<Real>::from_scene(world);
    REQUIRE(lights.size() == 1);
    CHECK(prism::scene::light_kinds(world) == prism::scene::bit(prism::DirectionalLight<Real>::kind));
    const glm::dvec3 towards = -glm::normalize(glm::dvec3(1, -0.8, -1));
    for (const auto& point : {prism::Vec3<Real>(0), prism::Vec3<Real>(1000, -5, 3)}) {
        const prism::LightSample<Real> sample = lights[0].sample({point});
        CHECK(std::isinf(sample.distance));
        for (int c = 0; c < 3; ++c) CHECK(sample.direction[c] == doctest::Approx(towards[c]).epsilon(1e-6));
        CHECK(glm::dvec3(sample.radiance) == glm::dvec3(200, 150, 100));
    }
}

TEST_CASE_TEMPLATE("SpotLight: inside, across and outside the cone, with inverse-square falloff", Real, float, double) {
    const auto spot = prism::SpotLight<Real>::from_description(downward_spot());
    const glm::dvec3 intensity(400, 200, 100);
    // Every angle from the axis to beyond the cover, at distances 2 and 5.
    for (double distance : {2.0, 5.0}) {
        for (double alpha = 0; alpha <= 40; alpha += 0.5) {
            CAPTURE(distance);
            CAPTURE(alpha);
            const prism::LightSample<Real> sample = spot.sample({point_at<Real>(alpha, distance)});
            CHECK(sample.distance == doctest::Approx(distance).epsilon(1e-6));
            const glm::dvec3 expected = intensity * course_spot_factor(alpha, 60, 40) / (distance * distance);
            for (int c = 0; c < 3; ++c) CHECK(double(sample.radiance[c]) == doctest::Approx(expected[c]).epsilon(1e-4).scale(1e-3));
            // The direction points back at the light.
            const glm::dvec3 back = -glm::normalize(glm::dvec3(point_at<double>(alpha, distance)));
            for (int c = 0; c < 3; ++c) CHECK(double(sample.direction[c]) == doctest::Approx(back[c]).epsilon(1e-5).scale(1e-5));
        }
    }
    // By hand, halfway between the edges (alpha 25): ((cos 25 - cos 30) / (cos 20 - cos 30))^4
    // = (0.040276 / 0.073667)^4 = 0.089353; at distance 2, 400 / 4 times that.
    CHECK(double(spot.sample({point_at<Real>(25, 2)}).radiance.r) == doctest::Approx(100 * 0.089353).epsilon(1e-3));
    CHECK(double(spot.sample({point_at<Real>(10, 2)}).radiance.r) == doctest::Approx(100).epsilon(1e-5));
    CHECK(spot.sample({point_at<Real>(31, 2)}).radiance == prism::Vec3<Real>(0));
    CHECK(spot.sample({point_at<Real>(150, 2)}).radiance == prism::Vec3<Real>(0));  // behind the light
}

TEST_CASE_TEMPLATE("SpotLight: no ring at the falloff edge or the coverage edge", Real, float, double) {
    for (const auto& angles : {std::pair{60.0, 40.0}, std::pair{10.0, 8.0}, std::pair{120.0, 30.0}}) {
        const double coverage = angles.first, falloff = angles.second;
        CAPTURE(coverage);
        CAPTURE(falloff);
        const auto spot = prism::SpotLight<Real>::from_description(downward_spot(coverage, falloff));
        const auto factor = [&](double alpha) { return double(spot.sample({point_at<Real>(alpha, 1)}).radiance.r) / 400; };
        // The factor's slope just outside the falloff edge is 4 sin(falloff/2) / (cos(falloff/2) -
        // cos(coverage/2)) per radian, 204 for the course's 10/8 degree cone: a step of 1e-6
        // degrees moves a continuous factor by 4e-6, so a larger jump is a ring.
        const double step = 1e-6;  // degrees
        CHECK(factor(falloff / 2 - step) == doctest::Approx(1.0).epsilon(1e-4));
        CHECK(std::abs(factor(falloff / 2 + step) - factor(falloff / 2 - step)) < 1e-4);
        CHECK(factor(coverage / 2 - step) < 1e-4);
        CHECK(factor(coverage / 2 + step) < 1e-4);
        // Non-increasing from the axis to the cover: no bright band anywhere across.
        double previous = 1;
        for (double alpha = falloff / 2; alpha <= coverage / 2 + 1; alpha += (coverage - falloff) / 400) {
            const double value = factor(alpha);
            CHECK(value <= previous + 1e-6);
            previous = value;
        }
    }
}

TEST_CASE_TEMPLATE("SpotLight: equal angles make a hard edge without dividing by zero", Real, float, double) {
    const auto spot = prism::SpotLight<Real>::from_description(downward_spot(40, 40));
    CHECK(double(spot.falloff(spot.cos_half_falloff)) == 1.0);
    CHECK(double(spot.sample({point_at<Real>(19.9, 1)}).radiance.r) == doctest::Approx(400));
    CHECK(double(spot.sample({point_at<Real>(20.1, 1)}).radiance.r) == 0.0);
}

namespace {

// A floor (the plane y = 0) seen straight down from (0, 5, 0), diffuse 0.5, no ambient.
scene::Scene floor_scene() {
    scene::Scene world;
    scene::Camera camera;
    camera.position = {0, 5, 0};
    camera.gaze = {0, -1, 0};
    camera.up = {0, 0, -1};
    camera.near_left = camera.near_bottom = -0.01;
    camera.near_right = camera.near_top = 0.01;
    camera.width = camera.height = 1;
    world.cameras.push_back(camera);
    scene::Material matte;
    matte.diffuse = {0.5, 0.5, 0.5};
    world.materials.push_back(matte);
    world.planes.push_back({"floor", 0, {0, 0, 0}, {0, 1, 0}, glm::dmat4(1.0)});
    return world;
}

}  // namespace

TEST_CASE_TEMPLATE("Renderer: a directional light lights the floor at any distance; shadow rays reach infinity", Real,
                   float, double) {
    using Punctual = prism::Config<Real, prism::Bvh<prism::Watertight>, prism::AllLightSet>;
    scene::Scene world = floor_scene();
    world.directional_lights.push_back({"sun", {0, -1, -1}, {100, 100, 100}});  // 45 degrees
    const prism::Ray<Real> down{prism::Vec3<Real>(0, 5, 0), prism::Vec3<Real>(0, -1, 0)};
    {
        const prism::Renderer<Punctual> renderer(world);
        // kd cos(theta) E = 0.5 * cos 45 * 100.
        CHECK(double(renderer.radiance(down).r) == doctest::Approx(50 / std::sqrt(2.0)).epsilon(1e-4));
    }
    // A sphere far along the way to the light blocks it: the shadow ray is not cut short.
    world.spheres.push_back({"far", 0, {0, 1000, 1000}, 10, glm::dmat4(1.0)});
    const prism::Renderer<Punctual> renderer(world);
    CHECK(double(renderer.radiance(down).r) == 0.0);
}

TEST_CASE_TEMPLATE("Renderer: a spot light on the floor follows the cone", Real, float, double) {
    using Punctual = prism::Config<Real, prism::Bvh<prism::Watertight>, prism::AllLightSet>;
    scene::Scene world = floor_scene();
    scene::SpotLight spot = downward_spot();
    spot.position = {0, 2, 0};
    world.spot_lights.push_back(spot);
    const prism::Renderer<Punctual> renderer(world);
    // Straight below, at distance 2, facing the light: 0.5 * 400 / 4.
    CHECK(double(renderer.radiance({prism::Vec3<Real>(0, 5, 0), prism::Vec3<Real>(0, -1, 0)}).r) ==
          doctest::Approx(50).epsilon(1e-4));
    // At 25 degrees off the axis: distance 2 / cos 25, cos(theta) = cos 25, factor 0.089353.
    const double alpha = 25 * degrees;
    const prism::Vec3<Real> target(Real(2 * std::tan(alpha)), 0, 0);
    const prism::Vec3<Real> eye(0, 5, 0);
    const double distance = 2 / std::cos(alpha);
    CHECK(double(renderer.radiance({eye, glm::normalize(target - eye)}).r) ==
          doctest::Approx(0.5 * std::cos(alpha) * 400 * 0.089353 / (distance * distance)).epsilon(1e-3));
}

TEST_CASE("render_scene: a light set without the scene's light type refuses the scene") {
    scene::Scene world = floor_scene();
    world.spot_lights.push_back(downward_spot());
    std::ostringstream log;
    const auto ignore = [](std::size_t, int) {};
    CHECK_THROWS_WITH_AS(
        (prism::detail::render_with<prism::Config<float, prism::Bvh<prism::Watertight>, prism::PointLightSet>>(
            world, prism::RenderOptions{}, log, ignore)),
        doctest::Contains("the scene needs spot lights, which this renderer was compiled without"), std::invalid_argument);
    // The dispatcher picks the complete renderer for it, and says why.
    const auto images = prism::render_scene(world, prism::RenderOptions{}, log);
    CHECK(images.size() == 1);
    CHECK(contains(log.str(), "all light types"));
    CHECK(contains(log.str(), "the scene has spot lights"));
}

// ---- the loader -----------------------------------------------------------------------------

namespace {

const char* const xml_scene = R"(<Scene>
    <Cameras>
        <Camera id="1">
            <Position>0 0 0</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
            <NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance>
            <ImageResolution>4 4</ImageResolution>
            <ImageName>hdr.exr</ImageName>
            <Tonemap>
                <TMO>Photographic</TMO>
                <TMOOptions>0.18 1</TMOOptions>
                <Saturation>1.0</Saturation>
                <Gamma>2.2</Gamma>
                <Extension>_phot.png</Extension>
            </Tonemap>
            <Tonemap>
                <TMO>ACES</TMO>
                <TMOOptions>0.36 0</TMOOptions>
                <Saturation>0.8</Saturation>
                <Gamma>2.4</Gamma>
                <Extension>_aces.png</Extension>
            </Tonemap>
            <Tonemap><TMO>Filmic</TMO><Extension>_filmic</Extension></Tonemap>
        </Camera>
    </Cameras>
    <Lights>
        <AmbientLight>25 25 25</AmbientLight>
        <DirectionalLight id="1">
            <Direction>1 -0.8 -1</Direction>
            <Radiance>200 200 200</Radiance>
        </DirectionalLight>
        <SpotLight id="2">
            <Position>-0.93 1 0.9</Position>
            <Direction>1 -1 -1</Direction>
            <Intensity>600 500 400</Intensity>
            <CoverageAngle>10</CoverageAngle>
            <FalloffAngle>8</FalloffAngle>
        </SpotLight>
    </Lights>
    <Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>
    <VertexData>-0.5 0.5 -2 -0.5 -0.5 -2 0.5 -0.5 -2</VertexData>
    <Objects><Mesh id="1"><Material>1</Material><Faces>1 2 3</Faces></Mesh></Objects>
</Scene>)";

const char* const json_scene = R"({"Scene": {
    "Cameras": {"Camera": {"_id": "1", "Position": "0 0 0", "Gaze": "0 0 -1", "Up": "0 1 0",
        "NearPlane": "-1 1 -1 1", "NearDistance": "1", "ImageResolution": "4 4", "ImageName": "hdr.exr",
        "Tonemap": [
            {"TMO": "Photographic", "TMOOptions": "0.18 1", "Saturation": "1.0", "Gamma": "2.2", "Extension": "_phot.png"},
            {"TMO": "ACES", "TMOOptions": "0.36 0", "Saturation": "0.8", "Gamma": "2.4", "Extension": "_aces.png"},
            {"TMO": "Filmic", "Extension": "_filmic"}]}},
    "Lights": {"AmbientLight": "25 25 25",
        "DirectionalLight": {"_id": "1", "Direction": "1 -0.8 -1", "Radiance": "200 200 200"},
        "SpotLight": {"_id": "2", "Position": "-0.93 1 0.9", "Direction": "1 -1 -1", "Intensity": "600 500 400",
                      "CoverageAngle": "10", "FalloffAngle": "8"}},
    "Materials": {"Material": {"_id": "1", "DiffuseReflectance": "1 1 1"}},
    "VertexData": {"_data": "-0.5 0.5 -2 -0.5 -0.5 -2 0.5 -0.5 -2", "_type": "xyz"},
    "Objects": {"Mesh": {"_id": "1", "Material": "1", "Faces": {"_data": "1 2 3", "_type": "triangle"}}}
}})";

}  // namespace

TEST_CASE("loader: DirectionalLight, SpotLight and Tonemap in XML and JSON") {
    TemporaryFolder folder;
    const scene::Scene from_xml = prism::io::load_scene(folder.write("lights.xml", xml_scene));
    const scene::Scene from_json = prism::io::load_scene(folder.write("lights.json", json_scene));
    for (const scene::Scene* world : {&from_xml, &from_json}) {
        CAPTURE(world->source);
        CHECK(world->unsupported.empty());
        REQUIRE(world->directional_lights.size() == 1);
        CHECK(world->directional_lights[0].id == "1");
        CHECK(world->directional_lights[0].direction == glm::dvec3(1, -0.8, -1));
        CHECK(world->directional_lights[0].radiance == glm::dvec3(200));
        REQUIRE(world->spot_lights.size() == 1);
        const scene::SpotLight& spot = world->spot_lights[0];
        CHECK(spot.position == glm::dvec3(-0.93, 1, 0.9));
        CHECK(spot.direction == glm::dvec3(1, -1, -1));
        CHECK(spot.intensity == glm::dvec3(600, 500, 400));
        CHECK(spot.coverage_angle == 10);
        CHECK(spot.falloff_angle == 8);

        REQUIRE(world->cameras.size() == 1);
        const auto& tonemaps = world->cameras[0].tonemaps;
        REQUIRE(tonemaps.size() == 3);
        CHECK(tonemaps[0].tone_operator == scene::TonemapOperator::photographic);
        CHECK(tonemaps[0].key == 0.18);
        CHECK(tonemaps[0].burn_percent == 1);
        CHECK(tonemaps[0].saturation == 1.0);
        CHECK(tonemaps[0].gamma == 2.2);
        CHECK(tonemaps[0].extension == "_phot.png");
        CHECK(tonemaps[1].tone_operator == scene::TonemapOperator::aces);
        CHECK(tonemaps[1].key == 0.36);
        CHECK(tonemaps[1].burn_percent == 0);
        CHECK(tonemaps[1].saturation == 0.8);
        CHECK(tonemaps[1].gamma == 2.4);
        CHECK(tonemaps[2].tone_operator == scene::TonemapOperator::filmic);
        CHECK(tonemaps[2].key == 0.18);  // left out: the defaults
        CHECK(tonemaps[2].gamma == 2.2);
        CHECK(prism::tone_mapped_image_name("hdr.exr", tonemaps[2]) == fs::path("hdr_filmic.png"));
    }
}

TEST_CASE("loader: the CLI path writes the EXR and one PNG per Tonemap from one render") {
    TemporaryFolder folder;
    const scene::Scene world = prism::io::load_scene(folder.write("lights.xml", xml_scene));
    std::ostringstream log;
    const auto images = prism::render_scene(world, prism::RenderOptions{}, log);
    REQUIRE(images.size() == 1);
    const auto outputs = prism::camera_outputs(world.cameras[0]);
    REQUIRE(outputs.size() == 4);
    CHECK(outputs[0].name == fs::path("hdr.exr"));
    CHECK(outputs[1].name == fs::path("hdr_phot.png"));
    CHECK(outputs[2].name == fs::path("hdr_aces.png"));
    CHECK(outputs[3].name == fs::path("hdr_filmic.png"));
}

TEST_CASE("loader: faults in the new elements name the element") {
    TemporaryFolder folder;
    const auto broken = [&](const std::string& from, const std::string& to) {
        std::string xml = xml_scene;
        const std::size_t at = xml.find(from);
        REQUIRE(at != std::string::npos);
        xml.replace(at, from.size(), to);
        return load_error_of(folder.write("broken.xml", xml));
    };
    std::string message = broken("<FalloffAngle>8</FalloffAngle>", "<FalloffAngle>12</FalloffAngle>");
    CHECK(contains(message, "FalloffAngle"));
    CHECK(contains(message, "between 0 and the coverage angle"));
    message = broken("<CoverageAngle>10</CoverageAngle>", "<CoverageAngle>0</CoverageAngle>");
    CHECK(contains(message, "CoverageAngle"));
    message = broken("<CoverageAngle>10</CoverageAngle>", "");
    CHECK(contains(message, "missing <CoverageAngle>"));
    message = broken("<Direction>1 -0.8 -1</Direction>", "<Direction>0 0 0</Direction>");
    CHECK(contains(message, "DirectionalLight"));
    CHECK(contains(message, "the direction is zero"));
    message = broken("<Radiance>200 200 200</Radiance>", "<Radiance>200 200</Radiance>");
    CHECK(contains(message, "Radiance"));
    message = broken("<TMO>ACES</TMO>", "<TMO>Drago</TMO>");
    CHECK(contains(message, "TMO"));
    CHECK(contains(message, "unknown tone mapping operator \"Drago\""));
    message = broken("<TMOOptions>0.18 1</TMOOptions>", "<TMOOptions>0.18</TMOOptions>");
    CHECK(contains(message, "TMOOptions"));
    message = broken("<TMOOptions>0.18 1</TMOOptions>", "<TMOOptions>0.18 120</TMOOptions>");
    CHECK(contains(message, "burn percentage"));
    message = broken("<Gamma>2.4</Gamma>", "<Gamma>0</Gamma>");
    CHECK(contains(message, "gamma must be positive"));
    message = broken("<Extension>_aces.png</Extension>", "<Extension>_phot.png</Extension>");
    CHECK(contains(message, "write the same image \"hdr_phot.png\""));
    message = broken("<Extension>_aces.png</Extension>", "<Extension>_aces.exr</Extension>");
    CHECK(contains(message, "must end in .png"));
}
