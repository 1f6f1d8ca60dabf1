// Object lights (LightMesh, LightSphere): their densities against area and solid angle (and the
// spherical triangles LightMesh samples), their estimates against known irradiance, the
// triangle a hit on an emitting mesh names, the loader in XML and JSON, the renderer's view of their
// radiance, and the refusal of a renderer prism does not implement.
#include "chi_square.hpp"
#include "temporary_folder.hpp"

#include <prism/accel/accelerator.hpp>
#include <prism/geometry/scene_geometry.hpp>
#include <prism/io/load.hpp>
#include <prism/light/area_light.hpp>
#include <prism/light/light_mesh.hpp>
#include <prism/light/light_sphere.hpp>
#include <prism/render/render_scene.hpp>
#include <prism/sampling/random.hpp>
#include <prism/sampling/spherical_triangle.hpp>

#include <glm/gtc/matrix_transform.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

namespace {

namespace scene = prism::scene;
using prism_test::TemporaryFolder;

constexpr double pi = 3.14159265358979323846;

}  // namespace

// The barycentric coordinates (b1, b2) of where the ray from `from` along `direction` meets the
// plane of the triangle v0, v0 + e1, v0 + e2, and its distance; in double.
struct PlanePoint {
    double b1 = 0, b2 = 0, t = 0;
};
PlanePoint on_triangle_plane(const glm::dvec3& from, const glm::dvec3& direction, const glm::dvec3& v0,
                             const glm::dvec3& e1, const glm::dvec3& e2) {
    const glm::dvec3 normal = glm::cross(e1, e2);
    const double t = glm::dot(v0 - from, normal) / glm::dot(direction, normal);
    const glm::dvec3 q = from + t * direction - v0;
    const double d11 = glm::dot(e1, e1), d12 = glm::dot(e1, e2), d22 = glm::dot(e2, e2);
    const double q1 = glm::dot(q, e1), q2 = glm::dot(q, e2), determinant = d11 * d22 - d12 * d12;
    return {(d22 * q1 - d12 * q2) / determinant, (d11 * q2 - d12 * q1) / determinant, t};
}

TEST_CASE_TEMPLATE("SphericalTriangle: its solid angle, and directions uniform in it, every one on the triangle",
                   Real, float, double) {
    using prism::SphericalTriangle;
    // An octant seen from its corner subtends pi / 2; the four midpoint triangles of any
    // triangle add up to it.
    const SphericalTriangle octant(prism::Vec3<Real>(0), prism::Vec3<Real>(1, 0, 0), prism::Vec3<Real>(-1, 1, 0),
                                   prism::Vec3<Real>(-1, 0, 1));
    CHECK(octant.solid_angle() == doctest::Approx(pi / 2).epsilon(1e-6));
    struct View {
        glm::dvec3 from, v0, e1, e2;
    };
    // Far (3e-4 sr), at a middle distance, close above an edge and beside the plane, nearly in it
    // (the viewpoint a hundredth of the edge off the plane, beside the triangle).
    const View views[] = {{{0.2, -40, 0.1}, {0, 0, 0}, {1, 0, 0.2}, {0.1, 0.3, 1}},
                          {{0.2, -1, 0.1}, {0, 0, 0}, {1, 0, 0.2}, {0.1, 0.3, 1}},
                          {{0.5, 0.02, -0.01}, {0, 0, 0}, {1, 0, 0}, {0, 0, 1}},
                          {{-0.3, 0.01, 0.3}, {0, 0, 0}, {1, 0, 0}, {0, 0, 1}}};
    for (const View& view : views) {
        CAPTURE(view.from.y);
        const SphericalTriangle whole(prism::Vec3<Real>(view.from), prism::Vec3<Real>(view.v0),
                                      prism::Vec3<Real>(view.e1), prism::Vec3<Real>(view.e2));
        // The far view is below what LightMesh samples this way, and sampled here all the same.
        REQUIRE(whole.solid_angle() > 2e-4);
        // The triangle cut into m x m cells in its barycentric coordinates: cell (i, j) upright
        // (its corner at b = (i, j) / m) and, where it fits, the cell turned over beside it.
        const int m = 8;
        std::vector<double> solid_angles;
        std::vector<int> hits;
        std::vector<int> cell_of(2 * m * m, -1);
        for (int i = 0; i < m; ++i)
            for (int j = 0; i + j < m; ++j)
                for (int turned = 0; turned < 2 && i + j + turned < m; ++turned) {
                    const auto at = [&](double b1, double b2) { return view.v0 + (b1 / m) * view.e1 + (b2 / m) * view.e2; };
                    const glm::dvec3 p0 = turned ? at(i + 1, j + 1) : at(i, j);
                    const glm::dvec3 p1 = turned ? at(i, j + 1) : at(i + 1, j);
                    const glm::dvec3 p2 = turned ? at(i + 1, j) : at(i, j + 1);
                    cell_of[2 * (i * m + j) + turned] = int(solid_angles.size());
                    solid_angles.push_back(SphericalTriangle(view.from, p0, p1 - p0, p2 - p0).solid_angle());
                }
        double sum = 0;
        for (const double omega : solid_angles) sum += omega;
        CHECK(sum == doctest::Approx(whole.solid_angle()).epsilon(1e-6));
        hits.assign(solid_angles.size(), 0);
        prism::Random random(5);
        const int count = 100000;
        int off_triangle = 0;
        for (int k = 0; k < count; ++k) {
            const glm::dvec3 direction(whole.sample(random.uniform2<Real>()));
            CHECK(glm::length(direction) == doctest::Approx(1.0).epsilon(1e-5));
            const PlanePoint point = on_triangle_plane(view.from, direction, view.v0, view.e1, view.e2);
            const double slack = 1e-5;
            if (!(point.t > 0) || point.b1 < -slack || point.b2 < -slack || point.b1 + point.b2 > 1 + slack) {
                ++off_triangle;
                continue;
            }
            const int i = std::clamp(int(point.b1 * m), 0, m - 1), j = std::clamp(int(point.b2 * m), 0, m - 1 - i);
            const bool turned = point.b1 * m - i + point.b2 * m - j > 1 && i + j + 1 < m;
            ++hits[std::size_t(cell_of[2 * (i * m + j) + (turned ? 1 : 0)])];
        }
        CHECK(off_triangle == 0);
        // 64 cells, 63 degrees of freedom: directions follow the solid angle cell by cell.
        const double chi_square = prism_test::pearson_chi_square(solid_angles, hits, count - off_triangle);
        CHECK(chi_square < prism_test::chi_square_quantile_999(int(solid_angles.size()) - 1));
    }
}

TEST_CASE_TEMPLATE("SphericalTriangle::unsamplable_beyond: past it no view is samplable, and it is not far past",
                   Real, float, double) {
    using prism::SphericalTriangle;
    using V = prism::Vec3<Real>;
    prism::Random random(11);
    const auto unit = [&] {
        // A direction uniform on the sphere.
        const double z = 2 * random.uniform<double>() - 1, phi = 2 * pi * random.uniform<double>();
        const double r = std::sqrt(std::max(0.0, 1 - z * z));
        return glm::dvec3(r * std::cos(phi), r * std::sin(phi), z);
    };
    int checked = 0;
    for (int shape = 0; shape < 400; ++shape) {
        // Triangles from a hundredth to ten units across, slivers among them, far from the origin
        // for some, as LightMesh keeps them: a vertex, two edges, and the centroid, each rounded.
        const double size = std::pow(10.0, 3 * random.uniform<double>() - 2);
        const glm::dvec3 base = (shape % 4 == 0 ? 100.0 : 1.0) * unit();
        const glm::dvec3 e1 = size * unit(), e2 = size * (shape % 3 == 0 ? 1e-3 : 1.0) * unit();
        const V a(base), edge1(e1), edge2(e2), centroid(base + (e1 + e2) / 3.0);
        const Real bound = SphericalTriangle::unsamplable_beyond(a, edge1, edge2, centroid);
        REQUIRE(bound > 0);
        REQUIRE(std::isfinite(bound));
        for (int view = 0; view < 50; ++view) {
            // Just past the bound (by up to a thousandth), and along the normal on every tenth view.
            const glm::dvec3 normal = glm::normalize(glm::cross(e1, e2));
            const glm::dvec3 towards = view % 10 == 0 ? normal : unit();
            const double distance = std::sqrt(double(bound)) * (1 + 1e-3 * random.uniform<double>());
            const V viewpoint(glm::dvec3(centroid) + distance * towards);
            // The comparison LightMesh makes, in Real.
            const V to_centroid = centroid - viewpoint;
            if (!(glm::dot(to_centroid, to_centroid) > bound)) continue;
            ++checked;
            const SphericalTriangle seen(viewpoint, a, edge1, edge2);
            CHECK_FALSE(seen.samplable());
        }
    }
    CHECK(checked > 15000);
    // Seen broadside from the bound, an equilateral triangle still subtends more than half the
    // smallest samplable solid angle: the bound is not so loose that it skips nothing.
    const double side = 0.5;
    const glm::dvec3 p0(0, 0, 0), p1(side, 0, 0), p2(side / 2, side * std::sqrt(3.0) / 2, 0);
    const V centroid((p0 + p1 + p2) / 3.0);
    const Real bound = SphericalTriangle::unsamplable_beyond(V(p0), V(p1 - p0), V(p2 - p0), centroid);
    const glm::dvec3 broadside = glm::dvec3(centroid) + glm::dvec3(0, 0, std::sqrt(double(bound)));
    const double omega = SphericalTriangle(broadside, p0, p1 - p0, p2 - p0).solid_angle();
    CHECK(omega > 0.5 * SphericalTriangle::smallest_solid_angle);
    CHECK(omega < SphericalTriangle::smallest_solid_angle);
}

// How large a triangle looks from `from` (LightMesh's weight, written out again in double):
// A |cos| / d^3 at its centroid, at most 2 pi.
double looks(const glm::dvec3& from, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    const glm::dvec3 cross = glm::cross(b - a, c - a), to_centroid = (a + b + c) / 3.0 - from;
    const double distance = glm::length(to_centroid);
    return std::min(2 * pi, glm::length(cross) / 2 * std::abs(glm::dot(glm::normalize(cross), to_centroid)) /
                                (distance * distance * distance));
}

TEST_CASE_TEMPLATE("LightMesh: a triangle chosen by how large it looks, then a direction uniform in its solid angle",
                   Real, float, double) {
    scene::Mesh mesh;
    // Two triangles of areas 0.5 and 1.5 in the plane y = 2.
    mesh.positions = {{0, 2, 0}, {1, 2, 0}, {0, 2, 1}, {4, 2, 0}};
    mesh.triangles = {{0, 1, 2}, {1, 3, 2}};
    mesh.radiance = {3, 2, 1};
    const auto light = prism::LightMesh<Real>::make(mesh, glm::dmat4(1.0), 0);
    CHECK(double(light.area) == doctest::Approx(2.0));
    prism::Random random(7);
    const glm::dvec3 from(0.5, 0, 0.25);
    const prism::ShadingFrame<Real> at{prism::Vec3<Real>(from), prism::Vec3<Real>(0, 1, 0)};
    const auto& p = mesh.positions;
    const double weight[2] = {looks(from, p[0], p[1], p[2]), looks(from, p[1], p[3], p[2])};
    const double chance_first = weight[0] / (weight[0] + weight[1]);
    // Each triangle's solid angle from `at`, in double from the file's vertices.
    const double omega[2] = {prism::SphericalTriangle(from, p[0], p[1] - p[0], p[2] - p[0]).solid_angle(),
                             prism::SphericalTriangle(from, p[1], p[3] - p[1], p[2] - p[1]).solid_angle()};
    REQUIRE(omega[0] >= prism::SphericalTriangle::smallest_solid_angle);
    REQUIRE(omega[1] >= prism::SphericalTriangle::smallest_solid_angle);
    int in_first = 0;
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
        const prism::LightSample<Real> sample = light.sample(at, random.uniform2<Real>());
        const prism::Vec3<Real> point = at.position + sample.direction * sample.distance;
        CHECK(double(point.y) == doctest::Approx(2.0).epsilon(1e-5));
        const bool first = point.x + point.z <= 1;
        in_first += first ? 1 : 0;
        // The chance of the triangle over its solid angle.
        const double expected = first ? chance_first / omega[0] : (1 - chance_first) / omega[1];
        CHECK(double(sample.pdf) == doctest::Approx(expected).epsilon(1e-4));
        CHECK(double(light.pdf(at, point, prism::Vec3<Real>(0, 1, 0), first ? 0 : 1)) == doctest::Approx(expected).epsilon(1e-4));
        CHECK(double(sample.radiance.r) == doctest::Approx(3.0 / expected).epsilon(1e-4));
    }
    // Binomial, 4 standard deviations.
    CHECK(std::abs(in_first - n * chance_first) < 4 * std::sqrt(n * chance_first * (1 - chance_first)));

    // Facing away, every triangle is below the point's horizon: no light, and no density.
    const prism::ShadingFrame<Real> away{at.position, prism::Vec3<Real>(0, -1, 0)};
    for (int i = 0; i < 100; ++i) CHECK(light.sample(away, random.uniform2<Real>()).radiance == prism::Vec3<Real>(0));
    CHECK(light.pdf(away, prism::Vec3<Real>(0.2, 2, 0.2), prism::Vec3<Real>(0, 1, 0), 0) == 0);

    // Seen from far away (each triangle under smallest_solid_angle), a point is sampled by area
    // instead, with the area density |x - q|^2 / (A_t |cos|) times the triangle's chance, and
    // pdf() says the same.
    const glm::dvec3 far_point(0.5, -200, 0.25);
    const prism::ShadingFrame<Real> far{prism::Vec3<Real>(far_point), prism::Vec3<Real>(0, 1, 0)};
    const double far_weight[2] = {looks(far_point, p[0], p[1], p[2]), looks(far_point, p[1], p[3], p[2])};
    for (int i = 0; i < 1000; ++i) {
        const prism::LightSample<Real> sample = light.sample(far, random.uniform2<Real>());
        const prism::Vec3<Real> point = far.position + sample.direction * sample.distance;
        const bool first = point.x + point.z <= 1;
        const double chance = far_weight[first ? 0 : 1] / (far_weight[0] + far_weight[1]);
        const double cos_light = std::abs(double(sample.direction.y));
        const double expected = chance * double(sample.distance) * double(sample.distance) / ((first ? 0.5 : 1.5) * cos_light);
        CHECK(double(sample.pdf) == doctest::Approx(expected).epsilon(1e-3));
        CHECK(double(light.pdf(far, point, prism::Vec3<Real>(0, 1, 0), first ? 0 : 1)) == doctest::Approx(expected).epsilon(1e-3));
    }
}

TEST_CASE_TEMPLATE("LightMesh: a mesh of more than 16 triangles chooses them by area", Real, float, double) {
    // 20 triangles side by side in the plane y = 2, triangle k over x in [k^2, (k + 1)^2] and z in
    // [0, 40]: areas 20 (2k + 1), the largest 39 times the smallest, 8000 in all.
    scene::Mesh mesh;
    const int count = 20;
    const double width = 40;
    for (int k = 0; k <= count; ++k) mesh.positions.push_back({double(k * k), 2, 0});
    for (int k = 0; k < count; ++k) {
        mesh.positions.push_back({double(k * k), 2, width});
        mesh.triangles.push_back({std::uint32_t(k), std::uint32_t(k + 1), std::uint32_t(count + 1 + k)});
    }
    mesh.radiance = {1, 1, 1};
    REQUIRE(mesh.triangles.size() > prism::LightMesh<Real>::weighed_by_view);
    const auto light = prism::LightMesh<Real>::make(mesh, glm::dmat4(1.0), 0);
    std::vector<double> areas;
    for (int k = 0; k < count; ++k) areas.push_back((2 * k + 1) / 2.0 * width);
    // From here about a third of the area is near enough to be sampled by solid angle.
    const prism::ShadingFrame<Real> at{prism::Vec3<Real>(200, -30, 20), prism::Vec3<Real>(0, 1, 0)};
    prism::Random random(3);
    std::vector<int> hits(areas.size(), 0);
    const int n = 40000;
    int samplable = 0;
    for (int i = 0; i < n; ++i) {
        const prism::LightSample<Real> sample = light.sample(at, random.uniform2<Real>());
        const glm::dvec3 point = glm::dvec3(at.position) + glm::dvec3(sample.direction) * double(sample.distance);
        const int k = std::clamp(int(std::sqrt(std::max(point.x, 0.0))), 0, count - 1);
        ++hits[std::size_t(k)];
        const glm::dvec3 a = mesh.positions[std::size_t(k)];
        const prism::SphericalTriangle view(glm::dvec3(at.position), a, mesh.positions[std::size_t(k + 1)] - a,
                                            mesh.positions[std::size_t(count + 1 + k)] - a);
        const double chance = areas[std::size_t(k)] / 8000.0, distance = double(sample.distance);
        // By solid angle where the triangle is large enough, else by area (the far ones).
        const double expected = view.samplable() ? chance / view.solid_angle()
                                                 : chance * distance * distance /
                                                       (areas[std::size_t(k)] * std::abs(double(sample.direction.y)));
        CHECK(double(sample.pdf) == doctest::Approx(expected).epsilon(1e-3));
        samplable += view.samplable() ? 1 : 0;
    }
    CHECK(prism_test::pearson_chi_square(areas, hits, n) < prism_test::chi_square_quantile_999(count - 1));
    // Both ways of sampling within a triangle were taken.
    CHECK(samplable > n / 10);
    CHECK(samplable < n - n / 10);
}

TEST_CASE_TEMPLATE("SphericalTriangle: samplable() answers as its solid angle does, at the smallest angle sampled too",
                   Real, float, double) {
    // Triangles of every shape, slivers among them, from viewpoints whose views range around
    // smallest_solid_angle: the views it takes as certainly smaller without their arctangent
    // (most of them) must be exactly those whose angle is smaller.
    using prism::SphericalTriangle;
    prism::Random random(17);
    int near_bound = 0, small = 0;
    const int count = 200000;
    for (int k = 0; k < count; ++k) {
        const auto point = [&] {
            return glm::dvec3(random.uniform<double>() - 0.5, random.uniform<double>() - 0.5, random.uniform<double>() - 0.5);
        };
        const prism::Vec3<Real> v0(point() * 20.0), edge1(point()), edge2(k % 4 == 0 ? glm::dvec3(edge1) * 1.001 : point());
        glm::dvec3 direction = point();
        if (!(glm::length(direction) > 1e-3)) continue;
        // The triangle's area over the squared distance, 0.01 to 1, bounds its solid angle.
        const double area = glm::length(glm::cross(glm::dvec3(edge1), glm::dvec3(edge2))) / 2;
        const double distance = std::sqrt(area / std::pow(10.0, 2 * random.uniform<double>() - 2));
        const glm::dvec3 centroid = glm::dvec3(v0) + (glm::dvec3(edge1) + glm::dvec3(edge2)) / 3.0;
        const prism::Vec3<Real> viewpoint(centroid + direction / glm::length(direction) * distance);
        const SphericalTriangle view(viewpoint, v0, edge1, edge2);
        const double omega = view.solid_angle();
        CAPTURE(k);
        CAPTURE(omega);
        REQUIRE(view.samplable() ==
                (omega >= SphericalTriangle::smallest_solid_angle && omega <= SphericalTriangle::largest_solid_angle));
        small += omega < SphericalTriangle::smallest_solid_angle ? 1 : 0;
        near_bound += omega >= SphericalTriangle::smallest_solid_angle && omega < 1.2 * SphericalTriangle::smallest_solid_angle;
    }
    // Both sides of the bound are well represented, and many views lie just above it.
    CHECK(small > count / 4);
    CHECK(small < count * 3 / 4);
    CHECK(near_bound > count / 50);
}

TEST_CASE_TEMPLATE("LightMesh: beside the light its estimates stay bounded, and their mean is Lambert's irradiance",
                   Real, float, double) {
    // A unit square at y = 1 and a point 0.01 below the plane, 0.02 beside its edge x = 0.5,
    // facing up: sampled by area, the estimate for the square's nearest corner of the edge was
    // up to L A cos cos / d^2 ~ 1000 L; by solid angle it is at most L Omega / P(triangle).
    scene::Mesh mesh;
    mesh.positions = {{-0.5, 1, -0.5}, {0.5, 1, -0.5}, {0.5, 1, 0.5}, {-0.5, 1, 0.5}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
    mesh.radiance = {1, 1, 1};
    const auto light = prism::LightMesh<Real>::make(mesh, glm::dmat4(1.0), 0);
    const glm::dvec3 from(0.52, 0.99, 0.1), normal(0, 1, 0);
    // Lambert's formula for a polygon wholly above the receiver's plane: E = L / 2 sum over edges
    // of the edge's angle times the normal's component along the edge's plane normal.
    double lambert = 0;
    for (int i = 0; i < 4; ++i) {
        const glm::dvec3 v0 = glm::normalize(mesh.positions[std::size_t(i)] - from);
        const glm::dvec3 v1 = glm::normalize(mesh.positions[std::size_t((i + 1) % 4)] - from);
        lambert += std::acos(glm::dot(v0, v1)) * glm::dot(normal, glm::normalize(glm::cross(v0, v1)));
    }
    lambert = std::abs(lambert) / 2;
    const prism::ShadingFrame<Real> at{prism::Vec3<Real>(from), prism::Vec3<Real>(normal)};
    prism::Random random(13);
    const int n = 200000;
    double sum = 0, largest = 0;
    for (int i = 0; i < n; ++i) {
        const auto sample = light.sample(at, random.uniform2<Real>());
        const double estimate = double(sample.radiance.g) * std::max(0.0, double(sample.direction.y));
        sum += estimate;
        largest = std::max(largest, estimate);
    }
    CHECK(sum / n == doctest::Approx(lambert).epsilon(0.005));
    // Each triangle is chosen with probability 1/2 and subtends less than 2 pi.
    CHECK(largest <= 4 * pi);
}

TEST_CASE_TEMPLATE("geometry: a hit on an emitting mesh names its triangle as the file and LightMesh number it", Real,
                   float, double) {
    // A 12 x 12 grid of 288 triangles (its own index reorders them) and an instance of it.
    scene::Scene world;
    world.materials.push_back({});
    scene::Mesh grid;
    const int cells = 12;
    for (int j = 0; j <= cells; ++j)
        for (int i = 0; i <= cells; ++i) grid.positions.push_back({i * 0.25, 2.0, j * 0.25});
    for (int j = 0; j < cells; ++j)
        for (int i = 0; i < cells; ++i) {
            const std::uint32_t v = std::uint32_t(j * (cells + 1) + i);
            grid.triangles.push_back({v, v + 1, v + cells + 2});
            grid.triangles.push_back({v, v + cells + 2, v + cells + 1});
        }
    grid.radiance = {1, 1, 1};
    world.meshes.push_back(grid);
    world.mesh_instances.push_back({"again", 0, 0, glm::translate(glm::dmat4(1.0), glm::dvec3(10, 0, 0)), {}, {}});
    using Policy = prism::WideBvh<prism::Watertight, 8>;
    const prism::SceneGeometry<Real, Policy> geometry(world);
    int reordered = 0;
    for (std::uint32_t object = 0; object < 2; ++object)
        for (std::uint32_t t = 0; t < grid.triangles.size(); ++t) {
            const auto& face = grid.triangles[t];
            const glm::dvec3 centroid = (grid.positions[face[0]] + grid.positions[face[1]] + grid.positions[face[2]]) / 3.0 +
                                        glm::dvec3(object * 10.0, 0, 0);
            prism::Ray<Real> ray{prism::Vec3<Real>(centroid - glm::dvec3(0, 1, 0)), prism::Vec3<Real>(0, 1, 0)};
            prism::Hit<Real> hit;
            REQUIRE(prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::none));
            CHECK(hit.object == object);
            CHECK(geometry.emitting_triangle(hit) == t);
            reordered += hit.primitive != t ? 1 : 0;
        }
    // Otherwise the mapping above would have nothing to do.
    CHECK(reordered > 0);
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
