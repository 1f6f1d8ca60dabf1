// Midpoint subdivision and the stress meshes, for float and double: four times the triangles per
// level, closed meshes stay closed and keep their winding, new vertices lie on the original
// triangles, the perturbed icosphere is closed and stays within its amplitude, seeds repeat;
// and the course's dragon_lowres reaches the tiny-triangle dragon's 750,000 triangles.
#include <prism/geometry/subdivide.hpp>
#include <prism/io/load.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif

namespace {

// A closed cube of 12 triangles, wound counter-clockwise seen from outside, placed at `offset`
// with half-size `half`.
template <class Real>
prism::IndexedMesh<Real> cube(Real half, prism::Vec3<Real> offset) {
    prism::IndexedMesh<Real> mesh;
    for (int i = 0; i < 8; ++i)
        mesh.positions.push_back(offset + half * prism::Vec3<Real>((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1));
    mesh.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                      {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
    return mesh;
}

template <class Real>
glm::dvec3 face_normal(const prism::IndexedMesh<Real>& mesh, std::size_t t) {
    const auto& tri = mesh.triangles[t];
    const glm::dvec3 p0(mesh.positions[tri[0]]), p1(mesh.positions[tri[1]]), p2(mesh.positions[tri[2]]);
    return glm::cross(p1 - p0, p2 - p0);
}

// Six times the enclosed volume (divergence theorem): positive when the winding faces outwards.
template <class Real>
double signed_volume_times_6(const prism::IndexedMesh<Real>& mesh) {
    double sum = 0.0;
    for (const auto& tri : mesh.triangles)
        sum += glm::dot(glm::dvec3(mesh.positions[tri[0]]),
                        glm::cross(glm::dvec3(mesh.positions[tri[1]]), glm::dvec3(mesh.positions[tri[2]])));
    return sum;
}

}  // namespace

TEST_CASE_TEMPLATE("midpoint subdivision multiplies the triangles by 4 per level and keeps a closed mesh closed", Real,
                   float, double) {
    const auto original = cube<Real>(Real(1), prism::Vec3<Real>(0));
    REQUIRE(prism::is_closed(original.triangles));
    for (int levels = 0; levels <= 4; ++levels) {
        CAPTURE(levels);
        const auto refined = prism::subdivide_midpoint(original, levels);
        CHECK(refined.triangles.size() == original.triangles.size() * (std::size_t(1) << (2 * levels)));
        // Euler: V - E + F = 2 for a closed genus-0 surface, E = 3F/2.
        CHECK(refined.positions.size() == 2 + refined.triangles.size() / 2);
        CHECK(prism::is_closed(refined.triangles));
        CHECK(signed_volume_times_6(refined) == doctest::Approx(6.0 * 8.0).epsilon(1e-5));
    }
}

TEST_CASE_TEMPLATE("subdivided vertices lie on their original triangle, children wound as their parent", Real, float,
                   double) {
    // Far from the origin and small, where rounding matters most.
    const prism::Vec3<Real> offset(Real(1000), Real(-2000), Real(500));
    const Real half = Real(1e-2);
    const auto original = cube<Real>(half, offset);
    constexpr int levels = 3;
    const auto refined = prism::subdivide_midpoint(original, levels);
    const std::size_t children = std::size_t(1) << (2 * levels);
    REQUIRE(refined.triangles.size() == original.triangles.size() * children);
    // Each midpoint is rounded once to Real from an exact midpoint of rounded points: the error
    // grows by at most half an ulp of the coordinates per level.
    const double tolerance = levels * double(std::numeric_limits<Real>::epsilon()) * 2000.0 * 2.0;
    std::size_t off_triangle = 0, flipped = 0;
    for (std::size_t t = 0; t < original.triangles.size(); ++t) {
        const auto& tri = original.triangles[t];
        const glm::dvec3 a(original.positions[tri[0]]), b(original.positions[tri[1]]), c(original.positions[tri[2]]);
        const glm::dvec3 normal = glm::cross(b - a, c - a);
        const glm::dvec3 unit_normal = glm::normalize(normal);
        for (std::size_t child = t * children; child < (t + 1) * children; ++child) {
            if (glm::dot(face_normal(refined, child), normal) <= 0) ++flipped;
            for (std::uint32_t v : refined.triangles[child]) {
                const glm::dvec3 p(refined.positions[v]);
                // Distance to the plane, and barycentric coordinates inside [0, 1] (with the
                // tolerance scaled to the triangle's size).
                const double plane_distance = std::abs(glm::dot(p - a, unit_normal));
                const double area2 = glm::dot(normal, normal);
                const double u = glm::dot(glm::cross(c - b, p - b), normal) / area2;
                const double w = glm::dot(glm::cross(a - c, p - c), normal) / area2;
                const double relative = tolerance / (2 * double(half));
                if (plane_distance > tolerance || u < -relative || w < -relative || u + w > 1 + relative)
                    ++off_triangle;
            }
        }
    }
    CHECK(off_triangle == 0);
    CHECK(flipped == 0);
}

TEST_CASE_TEMPLATE("the perturbed icosphere is closed, outward-facing and within its amplitude", Real, float, double) {
    for (int subdivisions : {0, 1, 3}) {
        CAPTURE(subdivisions);
        auto sphere = prism::icosphere<Real>(subdivisions);
        CHECK(sphere.triangles.size() == 20 * (std::size_t(1) << (2 * subdivisions)));
        CHECK(prism::is_closed(sphere.triangles));
        for (const auto& p : sphere.positions) CHECK(glm::length(glm::dvec3(p)) == doctest::Approx(1.0).epsilon(1e-6));
        const double amplitude = 0.05;
        prism::perturb_radially(sphere, prism::Vec3<Real>(0), amplitude, 42);
        CHECK(prism::is_closed(sphere.triangles));
        CHECK(signed_volume_times_6(sphere) > 0);
        double smallest = 2, largest = 0;
        for (const auto& p : sphere.positions) {
            smallest = std::min(smallest, glm::length(glm::dvec3(p)));
            largest = std::max(largest, glm::length(glm::dvec3(p)));
        }
        CHECK(smallest >= 1 - amplitude - 1e-6);
        CHECK(largest <= 1 + amplitude + 1e-6);
        CHECK(largest - smallest > amplitude);  // it did move the vertices
    }
}

TEST_CASE_TEMPLATE("perturbed subdivision stays closed, and a seed names one mesh", Real, float, double) {
    const auto original = prism::icosphere<Real>(1);
    prism::SubdivisionOptions options;
    options.perturb = 0.1;
    options.seed = 7;
    const auto first = prism::subdivide_midpoint(original, 2, options);
    const auto again = prism::subdivide_midpoint(original, 2, options);
    options.seed = 8;
    const auto other = prism::subdivide_midpoint(original, 2, options);
    CHECK(prism::is_closed(first.triangles));
    CHECK(first.positions == again.positions);
    CHECK(first.positions != other.positions);
    // Original vertices do not move; only midpoints do.
    CHECK(std::equal(original.positions.begin(), original.positions.end(), first.positions.begin()));

    auto sphere_a = prism::icosphere<Real>(2), sphere_b = prism::icosphere<Real>(2);
    prism::perturb_radially(sphere_a, prism::Vec3<Real>(0), 0.01, 3);
    prism::perturb_radially(sphere_b, prism::Vec3<Real>(0), 0.01, 3);
    CHECK(sphere_a.positions == sphere_b.positions);
}

TEST_CASE("is_closed finds open, non-manifold and inconsistently wound meshes") {
    using Triangles = std::vector<std::array<std::uint32_t, 3>>;
    auto closed = cube<double>(1.0, prism::Vec3<double>(0)).triangles;
    CHECK(prism::is_closed(closed));
    Triangles open(closed.begin(), closed.end() - 1);
    CHECK_FALSE(prism::is_closed(open));
    Triangles flipped = closed;
    std::swap(flipped[3][1], flipped[3][2]);
    CHECK_FALSE(prism::is_closed(flipped));
    Triangles doubled = closed;
    doubled.insert(doubled.end(), closed.begin(), closed.end());
    CHECK_FALSE(prism::is_closed(doubled));
    CHECK_FALSE(prism::is_closed(Triangles{{0, 0, 1}}));
    CHECK(prism::is_closed(Triangles{}));
    CHECK_THROWS_AS(prism::subdivide_midpoint(prism::IndexedMesh<float>{}, -1), std::invalid_argument);
    prism::IndexedMesh<float> sphere = prism::icosphere<float>(0);
    CHECK_THROWS_AS(prism::perturb_radially(sphere, prism::Vec3<float>(0), 1.0, 1), std::invalid_argument);
}

TEST_CASE("the course's dragon_lowres subdivided three times is the tiny-triangle dragon (>= 750,000 triangles)") {
    const std::filesystem::path file =
        std::filesystem::path(PRISM_SHARED_DIR) / "ceng795/hw1/2020_ozgurcanc/assets/scenes/dragon_lowres.xml";
    if (!std::filesystem::exists(file)) {
        MESSAGE("skipped: " << file << " not found");
        return;
    }
    const prism::scene::Scene scene = prism::io::load_scene(file);
    const auto largest = std::max_element(scene.meshes.begin(), scene.meshes.end(), [](const auto& a, const auto& b) {
        return a.triangles.size() < b.triangles.size();
    });
    REQUIRE(largest != scene.meshes.end());
    const prism::IndexedMesh<double> original = prism::world_space_mesh(*largest);
    const auto dragon = prism::subdivide_midpoint(original, 3);
    CHECK(dragon.triangles.size() >= 750000);
    CHECK(dragon.triangles.size() == 64 * original.triangles.size());
    // The surface keeps its size: the bounding boxes agree.
    glm::dvec3 lo_a(1e300), hi_a(-1e300), lo_b(1e300), hi_b(-1e300);
    for (const auto& p : original.positions) lo_a = glm::min(lo_a, p), hi_a = glm::max(hi_a, p);
    for (const auto& p : dragon.positions) lo_b = glm::min(lo_b, p), hi_b = glm::max(hi_b, p);
    CHECK(glm::length(lo_a - lo_b) < 1e-12);
    CHECK(glm::length(hi_a - hi_b) < 1e-12);
}
