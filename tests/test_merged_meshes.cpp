// SceneGeometry's merged world-space index (geometry/scene_geometry.hpp): the meshes without a
// transformation share one index over all their triangles, yet every hit still names its own
// mesh's object and its triangle in that mesh, back-face culling still follows each mesh's
// shading, and transformed, instanced and moving meshes stay in the top level. Brute force
// (which merges nothing) is the reference, to the bit.
#include <prism/accel/accelerator.hpp>
#include <prism/geometry/double_refine.hpp>
#include <prism/geometry/scene_geometry.hpp>

#include <glm/gtc/matrix_transform.hpp>

#include <doctest/doctest.h>

#include <cstddef>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace {

namespace scene = prism::scene;

// A k x k grid of triangle pairs in the plane z = height, facing +z, shifted by `shift` in x, as
// a vertex soup whose triangle i carries the texture coordinate (i, tag) at every vertex: the
// interpolated (u, v) of a hit names the triangle and the mesh whatever the index's order.
scene::Mesh grid(int k, double height, double shift, double tag) {
    scene::Mesh mesh;
    auto add = [&](glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
        const double i = double(mesh.triangles.size());
        const auto first = std::uint32_t(mesh.positions.size());
        for (const auto& p : {a, b, c}) {
            mesh.positions.push_back(p);
            mesh.uvs.push_back({i, tag});
        }
        mesh.triangles.push_back({first, first + 1, first + 2});
    };
    for (int y = 0; y < k; ++y)
        for (int x = 0; x < k; ++x) {
            const glm::dvec3 corner(shift + x, y, height);
            add(corner, corner + glm::dvec3(1, 0, 0), corner + glm::dvec3(1, 1, 0));
            add(corner, corner + glm::dvec3(1, 1, 0), corner + glm::dvec3(0, 1, 0));
        }
    return mesh;
}

glm::dvec3 centroid(const scene::Mesh& mesh, std::size_t triangle) {
    const auto& face = mesh.triangles[triangle];
    return (mesh.positions[face[0]] + mesh.positions[face[1]] + mesh.positions[face[2]]) / 3.0;
}

// Three overlapping grids in world space with an empty mesh among them (merged), a translated
// grid and a grid placed again by an instance (both kept in the top level), and a sphere.
scene::Scene overlapping_meshes() {
    scene::Scene world;
    world.materials.push_back({});
    world.meshes.push_back(grid(4, 0.0, 0.0, 0));
    world.meshes.push_back({});  // no triangles: merged, and names nothing
    world.meshes.push_back(grid(4, 0.5, 0.3, 2));
    world.meshes.push_back(grid(4, 1.0, 0.6, 3));
    world.meshes.push_back(grid(4, 0.0, 0.0, 4));
    world.meshes.back().transform = glm::translate(glm::dmat4(1.0), glm::dvec3(10, 0, 0));
    world.meshes.push_back(grid(4, 0.0, 0.0, 5));
    world.meshes.back().shading = scene::ShadingMode::smooth;
    world.meshes.back().transform = glm::translate(glm::dmat4(1.0), glm::dvec3(-10, 0, 0));
    world.mesh_instances.push_back({"again", 5, 0, glm::translate(glm::dmat4(1.0), glm::dvec3(-20, 0, 0)), {}, {}});
    world.spheres.push_back({"ball", 0, {2, 2, 5}, 0.5});
    return world;
}

// Every triangle of every mesh, and the instance's, hit at its centroid from 0.125 above (the
// next grid is 0.5 away), compared with brute force: the same object, triangle, t, barycentrics,
// surface and leaving origin, to the bit; any-hit below and beyond the triangle too.
template <class Real, class Intersector, class Policy>
void compare_with_brute_force(const scene::Scene& world) {
    const prism::SceneGeometry<Real, Policy> merged(world);
    const prism::SceneGeometry<Real, prism::BruteForce<Intersector>> brute(world);
    CHECK(merged.merged_mesh_count() == 4);
    CHECK(brute.merged_mesh_count() == 0);
    CHECK(merged.instance_count() == brute.instance_count());
    CHECK(merged.triangle_count() == brute.triangle_count());
    CHECK(merged.bounds().min == brute.bounds().min);
    CHECK(merged.bounds().max == brute.bounds().max);
    CHECK(merged.accelerator_bytes() > 0);

    std::size_t rays = 0, wrong_object = 0, wrong_triangle = 0, differ = 0, occluded_wrong = 0;
    auto trace = [&](std::uint32_t object, std::size_t triangle, glm::dvec3 target, double tag) {
        const bool merged_object = object < 4;
        const prism::Ray<Real> start{prism::Vec3<Real>(target + glm::dvec3(0, 0, 0.125)), prism::Vec3<Real>(0, 0, -1)};
        prism::Ray<Real> ray = start, reference_ray = start;
        prism::Hit<Real> hit, reference;
        ++rays;
        if (!prism::closest_hit(merged, ray, hit) || !prism::closest_hit(brute, reference_ray, reference)) {
            ++differ;
            return;
        }
        const prism::SurfacePoint<Real> point = merged.surface(ray, hit);
        if (hit.object != object) ++wrong_object;
        if (std::lround(double(point.uv.x)) != long(triangle) || std::lround(double(point.uv.y)) != long(tag)) ++wrong_triangle;
        const prism::SurfacePoint<Real> expected = brute.surface(reference_ray, reference);
        const prism::Vec3<Real> up(0, 0, 1);
        // A merged mesh keeps its triangles in the file's order, as brute force does; the
        // others in their own index's order.
        if (merged_object && hit.primitive != reference.primitive) ++differ;
        if (hit.object != reference.object || hit.t != reference.t ||
            hit.b1 != reference.b1 || hit.b2 != reference.b2 || ray.t_max != reference_ray.t_max ||
            point.position != expected.position || point.shading_normal != expected.shading_normal ||
            merged.spawn_origin(point, up) != brute.spawn_origin(expected, up))
            ++differ;
        prism::Ray<Real> shadow = start;
        shadow.t_max = Real(0.0625);
        if (prism::blocked(merged, shadow)) ++occluded_wrong;
        shadow.t_max = Real(1);
        if (!prism::blocked(merged, shadow)) ++occluded_wrong;
    };
    const glm::dvec3 instance_offset(-10, 0, 0);  // the instance's place relative to its mesh's
    for (std::uint32_t m = 0; m < world.meshes.size(); ++m) {
        const scene::Mesh& mesh = world.meshes[m];
        const glm::dvec3 offset = glm::dvec3(mesh.transform[3]);
        for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
            trace(m, i, centroid(mesh, i) + offset, m);
            if (m == 5) trace(std::uint32_t(world.meshes.size()), i, centroid(mesh, i) + offset + instance_offset, m);
        }
    }
    CHECK(rays == 6 * 32);
    CHECK(wrong_object == 0);
    CHECK(wrong_triangle == 0);
    CHECK(differ == 0);
    CHECK(occluded_wrong == 0);

    // The sphere, in the top level beside the merged index.
    prism::Ray<Real> ray{prism::Vec3<Real>(2, 2, 10), prism::Vec3<Real>(0, 0, -1)};
    prism::Hit<Real> hit;
    REQUIRE(prism::closest_hit(merged, ray, hit));
    CHECK(hit.object == world.meshes.size() + 1);
    CHECK(hit.t == doctest::Approx(4.5).epsilon(1e-6));
    // Below the sphere a ray meets the merged grids, the nearest at z = 1 (mesh 3).
    ray = {prism::Vec3<Real>(2.1, 2.1, 4), prism::Vec3<Real>(0, 0, -1)};
    REQUIRE(prism::closest_hit(merged, ray, hit));
    CHECK(hit.object == 3);
    CHECK(hit.t == doctest::Approx(3).epsilon(1e-6));
}

}  // namespace

TEST_CASE_TEMPLATE("Merged world-space meshes: each hit names its own mesh and triangle, as brute force does", Real,
                   float, double) {
    const scene::Scene world = overlapping_meshes();
    compare_with_brute_force<Real, prism::Watertight, prism::Bvh<prism::Watertight>>(world);
    compare_with_brute_force<Real, prism::Watertight, prism::WideBvh<prism::Watertight, 4>>(world);
    compare_with_brute_force<Real, prism::Watertight, prism::WideBvh<prism::Watertight, 8>>(world);
    compare_with_brute_force<Real, prism::DoubleRefine, prism::WideBvh<prism::DoubleRefine, 8>>(world);
}

TEST_CASE_TEMPLATE("Merged world-space meshes: back-face culling skips flat and smooth meshes alike", Real, float, double) {
    using prism::BackfaceCulling;
    scene::Scene world;
    world.materials.push_back({});
    scene::Mesh front;  // faces +z, at z = 0, flat
    front.positions = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
    front.triangles = {{0, 1, 2}};
    scene::Mesh smooth = front;  // faces +z, at z = -1, smooth
    smooth.shading = scene::ShadingMode::smooth;
    for (auto& p : smooth.positions) p.z = -1;
    scene::Mesh back = front;  // faces -z, at z = -2, flat
    back.triangles = {{0, 2, 1}};
    for (auto& p : back.positions) p.z = -2;
    scene::Mesh smooth_back = back;  // faces -z, at z = -3, smooth
    smooth_back.shading = scene::ShadingMode::smooth;
    for (auto& p : smooth_back.positions) p.z = -3;
    world.meshes = {front, smooth, back, smooth_back};
    const prism::Ray<Real> from_below{prism::Vec3<Real>(0, 0, -10), prism::Vec3<Real>(0, 0, 1)};
    const prism::Ray<Real> from_above{prism::Vec3<Real>(0, 0, 10), prism::Vec3<Real>(0, 0, -1)};
    // The first hit beyond t_min under each culling, as (object, t); object -1 is a miss.
    auto first_hit = [](const auto& geometry, prism::Ray<Real> ray, Real t_min, BackfaceCulling culling) {
        ray.t_min = t_min;
        prism::Hit<Real> hit;
        bool found = false;
        switch (culling) {
            case BackfaceCulling::none: found = prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::none); break;
            case BackfaceCulling::triangles:
                found = prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::triangles);
                break;
            case BackfaceCulling::all: found = prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::all); break;
        }
        return found ? std::pair<int, Real>(int(hit.object), hit.t) : std::pair<int, Real>(-1, Real(0));
    };
    auto check = [&]<class Geometry>() {
        const Geometry geometry(world);
        CHECK(geometry.merged_mesh_count() == 4);
        using P = std::pair<int, Real>;
        // From below: smooth_back (t 7) faces the ray; then back (8) faces it; smooth (9) and
        // front (10) face away.
        CHECK(first_hit(geometry, from_below, 0, BackfaceCulling::all) == P(3, 7));
        CHECK(first_hit(geometry, from_below, Real(8.5), BackfaceCulling::none) == P(1, 9));
        CHECK(first_hit(geometry, from_below, Real(8.5), BackfaceCulling::triangles) == P(-1, 0));
        CHECK(first_hit(geometry, from_below, Real(8.5), BackfaceCulling::all) == P(-1, 0));
        CHECK(first_hit(geometry, from_below, Real(9.5), BackfaceCulling::triangles) == P(-1, 0));
        CHECK(first_hit(geometry, from_below, Real(9.5), BackfaceCulling::none) == P(0, 10));
        // From above: front (10) and smooth (11) face the ray; back (12) and smooth_back (13)
        // face away: the course's rule skips both.
        CHECK(first_hit(geometry, from_above, 0, BackfaceCulling::all) == P(0, 10));
        CHECK(first_hit(geometry, from_above, Real(11.5), BackfaceCulling::none) == P(2, 12));
        CHECK(first_hit(geometry, from_above, Real(11.5), BackfaceCulling::triangles) == P(-1, 0));
        CHECK(first_hit(geometry, from_above, Real(11.5), BackfaceCulling::all) == P(-1, 0));
        // Shadow rays cull nothing.
        prism::Ray<Real> shadow = from_above;
        shadow.t_min = Real(12.5);
        CHECK(prism::blocked(geometry, shadow));
        shadow.t_max = Real(12.9);
        CHECK_FALSE(prism::blocked(geometry, shadow));
    };
    check.template operator()<prism::SceneGeometry<Real, prism::Bvh<prism::Watertight>>>();
    check.template operator()<prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 4>>>();
    check.template operator()<prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>>>();
}

TEST_CASE_TEMPLATE("Merged world-space meshes: moving meshes stay in the top level", Real, float, double) {
    scene::Scene world;
    world.materials.push_back({});
    world.meshes.push_back(grid(2, 0.0, 0.0, 0));
    world.meshes.push_back(grid(2, 1.0, 0.0, 1));
    world.meshes.back().motion = glm::dvec3(0, 0, 2);
    const prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>, true> moving(world);
    CHECK(moving.merged_mesh_count() == 1);
    // Without motion blur the motion is ignored, and both meshes are merged.
    const prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>, false> still(world);
    CHECK(still.merged_mesh_count() == 2);
    // At time 1 the moving grid is at z = 3: a ray from z = 4 down meets it at t = 1, and the
    // still grid at t = 4 once t_min is past it.
    prism::Ray<Real> ray{prism::Vec3<Real>(0.75, 0.25, 4), prism::Vec3<Real>(0, 0, -1)};
    ray.time = Real(1);
    prism::Hit<Real> hit;
    REQUIRE(prism::closest_hit(moving, ray, hit));
    CHECK(hit.object == 1);
    CHECK(hit.t == Real(1));
    ray = {prism::Vec3<Real>(0.75, 0.25, 4), prism::Vec3<Real>(0, 0, -1), Real(1.5)};
    ray.time = Real(1);
    REQUIRE(prism::closest_hit(moving, ray, hit));
    CHECK(hit.object == 0);
    CHECK(hit.t == Real(4));
}
