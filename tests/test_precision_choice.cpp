// The automatic precision choice: triangles measured against the magnitude of their coordinates
// decide float, double-precision triangle tests, or double throughout; --precision overrides.
#include <prism/math/transform.hpp>
#include <prism/render/render_scene.hpp>

#include <doctest/doctest.h>

namespace {

// One triangle with edges of length `edge`, placed at distance `offset` from the origin.
prism::scene::Scene scene_with_triangle(double edge, double offset) {
    prism::scene::Scene scene;
    prism::scene::Mesh mesh;
    mesh.positions = {{offset, 0, 0}, {offset + edge, 0, 0}, {offset, edge, 0}};
    mesh.triangles = {{0, 1, 2}};
    scene.meshes.push_back(mesh);
    scene.materials.emplace_back();
    return scene;
}

}  // namespace

TEST_CASE("triangles large against their coordinates render in float") {
    const auto choice = prism::choose_precision(scene_with_triangle(0.5, 1.0), {});
    CHECK(choice.precision == prism::Precision::single);
    CHECK(choice.reason.find("2^-") != std::string::npos);
}

TEST_CASE("tiny triangles get double-precision triangle tests") {
    // edge / magnitude = 1e-4, about 2^-13.3
    CHECK(prism::choose_precision(scene_with_triangle(1e-4, 1.0), {}).precision == prism::Precision::double_refine);
}

TEST_CASE("tiny triangles far from the origin get double throughout") {
    // edge / magnitude = 1e-4 / 1e4 = 1e-8, about 2^-26: below float's resolution
    CHECK(prism::choose_precision(scene_with_triangle(1e-4, 1e4), {}).precision == prism::Precision::double_all);
}

TEST_CASE("the thresholds sit at 2^-12 and 2^-16") {
    CHECK(prism::choose_precision(scene_with_triangle(0x1p-12 * 1.01, 1.0), {}).precision == prism::Precision::single);
    CHECK(prism::choose_precision(scene_with_triangle(0x1p-12 * 0.99, 1.0), {}).precision ==
          prism::Precision::double_refine);
    CHECK(prism::choose_precision(scene_with_triangle(0x1p-16 * 1.01, 1.0), {}).precision ==
          prism::Precision::double_refine);
    CHECK(prism::choose_precision(scene_with_triangle(0x1p-16 * 0.99, 1.0), {}).precision == prism::Precision::double_all);
}

TEST_CASE("--precision overrides the measurement") {
    prism::RenderOptions options;
    options.precision = prism::Precision::double_all;
    const auto choice = prism::choose_precision(scene_with_triangle(0.5, 1.0), options);
    CHECK(choice.precision == prism::Precision::double_all);
    CHECK(choice.reason == "requested with --precision");
}

TEST_CASE("a scene without triangles renders in float") {
    prism::scene::Scene scene;
    scene.spheres.push_back({"1", 0, {0, 0, 0}, 1.0});
    CHECK(prism::choose_precision(scene, {}).precision == prism::Precision::single);
}

TEST_CASE("a small sphere far from the origin renders in double throughout") {
    // radius / (|centre| + radius) = 0.3 / 10^4: about 2^-15, below 2^-12; the double-precision
    // triangle test would not help a sphere, so it is double throughout, triangles or not.
    prism::scene::Scene scene = scene_with_triangle(0.5, 1.0);
    scene.spheres.push_back({"far", 0, {1e4 - 0.3, 0, 0}, 0.3});
    const auto choice = prism::choose_precision(scene, {});
    CHECK(choice.precision == prism::Precision::double_all);
    CHECK(choice.reason.find("sphere") != std::string::npos);
    // the same sphere near the origin leaves the triangles to decide
    scene.spheres.back().center = {2, 0, 0};
    CHECK(prism::choose_precision(scene, {}).precision == prism::Precision::single);
}

TEST_CASE("a sphere's size is its shortest world axis") {
    prism::scene::Scene scene;
    scene.spheres.push_back({"flat", 0, {0, 0, 0}, 1.0});
    scene.spheres.back().transform = prism::translation({1.0, 0, 0}) * prism::scaling({1.0, 1e-5, 1.0});
    // radius 1e-5 along y against a magnitude of 1 + 1e-5: 2^-17
    CHECK(prism::choose_precision(scene, {}).precision == prism::Precision::double_all);
    scene.spheres.back().transform = glm::dmat4(1.0);
    CHECK(prism::choose_precision(scene, {}).precision == prism::Precision::single);
}
