// The shortcuts of scenes of a few spheres and planes, for float and double: a top level of at
// most 8 spheres tested one after another (SceneGeometry's direct spheres) finds the hits and
// the occlusions the top-level index finds, bit for bit, on random and grazing rays, with and
// without a world-space mesh beside it, for plain, translated and scaled-rotated spheres; and
// Blinn-Phong's power is left out only where the sum it enters is the same without it; and
// world-space meshes of a few triangles beside such a top level, tested leaf by leaf without
// their indices (their traversal ray, their root's box test), find the same hits, ties on the
// quads' diagonals and rays that start on or graze their boxes' faces included; and planes,
// tested eight at a time, give what each plane's own test gives, one after another; and shadow
// rays tested several at a time (one batch through occluded) get what each gets alone; and a
// world index whose root has two leaves gives a batch's rays, a ray in each lane leaf after leaf,
// the hits and answers each gets alone, ties on the edges the leaves share included.
#include "same_bits.hpp"

#include <prism/geometry/scene_geometry.hpp>
#include <prism/material/material.hpp>

#include <glm/gtc/matrix_transform.hpp>

#include <doctest/doctest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

using prism_test::same_bits;

namespace {

namespace scene = prism::scene;

// Spheres of every kind the direct test distinguishes, a plane, and optionally a floor of two
// triangles (a world-space mesh, tested before the top level).
// `more` adds four spheres in reach, for a top level of 8: the direct test's limit.
scene::Scene few_spheres(bool with_mesh, bool more = false) {
    scene::Scene world;
    world.materials.push_back({});
    world.spheres.push_back({"plain", 0, {0, 0, 0}, 1.0, glm::dmat4(1.0)});
    world.spheres.push_back({"translated", 0, {0.5, 0, 0}, 0.75,
                             glm::translate(glm::dmat4(1.0), glm::dvec3(2.5, 0.25, -1))});
    glm::dmat4 ellipsoid = glm::translate(glm::dmat4(1.0), glm::dvec3(-2.5, 0.5, 0.5));
    ellipsoid = glm::rotate(ellipsoid, 0.7, glm::normalize(glm::dvec3(1, 2, 3)));
    ellipsoid = glm::scale(ellipsoid, glm::dvec3(1.5, 0.25, 0.8));
    world.spheres.push_back({"ellipsoid", 0, {0, 0.2, 0}, 1.0, ellipsoid});
    world.spheres.push_back({"flattened", 0, {0, 0, 0}, 0.5,
                             glm::scale(glm::translate(glm::dmat4(1.0), glm::dvec3(0, 2.5, 0)), glm::dvec3(3, 0.1, 3))});
    world.planes.push_back({"wall", 0, {0, 0, -4}, glm::normalize(glm::dvec3(0.1, 0.2, 1)), glm::dmat4(1.0)});
    if (more) {
        world.spheres.push_back({"small", 0, {1, -1, 2}, 0.4, glm::dmat4(1.0)});
        world.spheres.push_back({"moved", 0, {0, 0, 0}, 0.6, glm::translate(glm::dmat4(1.0), glm::dvec3(-2, -0.5, 2.5))});
        world.spheres.push_back({"overlapping", 0, {0.8, 0.3, 0}, 0.5, glm::dmat4(1.0)});
        world.spheres.push_back({"stretched", 0, {0, 0, 0}, 0.3,
                                 glm::scale(glm::translate(glm::dmat4(1.0), glm::dvec3(2, 1.5, 2)), glm::dvec3(1, 4, 1))});
    }
    if (with_mesh) {
        scene::Mesh floor;
        floor.positions = {{-6, -1.5, -6}, {6, -1.5, -6}, {6, -1.5, 6}, {-6, -1.5, 6}};
        floor.triangles = {{0, 2, 1}, {0, 3, 2}};
        world.meshes.push_back(floor);
    }
    return world;
}

// A direction uniform on the sphere.
glm::dvec3 random_unit(std::mt19937& random) {
    std::uniform_real_distribution<double> uniform(-1, 1);
    glm::dvec3 v;
    do v = {uniform(random), uniform(random), uniform(random)};
    while (glm::dot(v, v) > 1 || glm::dot(v, v) < 1e-6);
    return glm::normalize(v);
}

// The same scene with `count` tiny spheres far beyond every ray's reach, which take its top
// level past the direct test's limit of 8: the same objects, through the index.
scene::Scene past_direct_limit(scene::Scene world, int count) {
    for (int i = 0; i < count; ++i) world.spheres.push_back({"far", 0, {1e4 + 10 * i, 1e4, 1e4}, 1e-3, glm::dmat4(1.0)});
    return world;
}

// Two closest hits of one ray, to the bit: the distance the ray was cut to, the triangle and
// where on it.
template <class Real>
void check_same_hit(const prism::Ray<Real>& a, const prism::Hit<Real>& hit_a, const prism::Ray<Real>& b,
                    const prism::Hit<Real>& hit_b) {
    CHECK(same_bits(hit_a.t, hit_b.t));
    CHECK(same_bits(a.t_max, b.t_max));
    CHECK(same_bits(hit_a.b1, hit_b.b1));
    CHECK(same_bits(hit_a.b2, hit_b.b2));
    CHECK(hit_a.object == hit_b.object);
    CHECK(hit_a.primitive == hit_b.primitive);
}

}  // namespace

TEST_CASE_TEMPLATE("SceneGeometry: a top level of a few spheres tested directly finds what the index finds", Real, float,
                   double) {
    using Geometry = prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>>;
    for (const bool more : {false, true})
    for (const bool with_mesh : {false, true}) {
        for (const prism::BackfaceCulling culling : {prism::BackfaceCulling::none, prism::BackfaceCulling::triangles}) {
        CAPTURE(int(culling));
        CAPTURE(with_mesh);
        CAPTURE(more);
        const scene::Scene direct_world = few_spheres(with_mesh, more);
        const Geometry direct(direct_world), indexed(past_direct_limit(direct_world, 5));

        std::mt19937 random(7);
        std::uniform_real_distribution<double> uniform(-1, 1);
        const auto unit = [&] { return random_unit(random); };
        // Points on each sphere's surface, in world space, for rays that pass through them or
        // just graze them (the rays the bounding spheres' margins are for).
        const auto surface_point = [&](std::size_t s) {
            const scene::Sphere& sphere = direct_world.spheres[s];
            return glm::dvec3(sphere.transform * glm::dvec4(sphere.center + sphere.radius * unit(), 1.0));
        };
        std::size_t hits = 0, blocked = 0, rays = 0;
        for (int i = 0; i < 60000; ++i) {
            glm::dvec3 origin, direction;
            if (i % 2 == 0) {
                origin = 5.0 * glm::dvec3(uniform(random), uniform(random), uniform(random));
                direction = unit();
            } else {
                const glm::dvec3 target = surface_point(std::size_t(i / 2) % direct_world.spheres.size());
                origin = target + (1 + 4 * std::abs(uniform(random))) * unit();
                direction = glm::normalize(target - origin);
                if (i % 4 == 1) direction = glm::normalize(direction + 1e-4 * unit());  // grazing, either side
            }
            prism::Ray<Real> ray{prism::Vec3<Real>(origin), prism::Vec3<Real>(direction), Real(0), Real(50)};
            if (i % 3 == 0) ray.t_max = Real(3 * std::abs(uniform(random)));
            ++rays;
            prism::Ray<Real> a = ray, b = ray;
            prism::Hit<Real> hit_a, hit_b;
            const bool found_a = culling == prism::BackfaceCulling::none
                                     ? prism::closest_hit(direct, a, hit_a)
                                     : prism::closest_hit(direct, a, hit_a, prism::BackfaceCulling::triangles);
            const bool found_b = culling == prism::BackfaceCulling::none
                                     ? prism::closest_hit(indexed, b, hit_b)
                                     : prism::closest_hit(indexed, b, hit_b, prism::BackfaceCulling::triangles);
            REQUIRE(found_a == found_b);
            CHECK(prism::blocked(direct, ray) == prism::blocked(indexed, ray));
            if (!found_a) continue;
            ++hits;
            blocked += prism::blocked(direct, ray);
            CHECK(same_bits(hit_a.t, hit_b.t));
            CHECK(same_bits(a.t_max, b.t_max));
            // Planes are numbered after the objects, so past the far spheres in the indexed scene.
            const auto plane_or_object = [](const Geometry& geometry, std::uint32_t object) {
                return object >= geometry.instance_count() ? 1000 + (object - geometry.instance_count()) : std::size_t(object);
            };
            CHECK(plane_or_object(direct, hit_a.object) == plane_or_object(indexed, hit_b.object));
            CHECK(hit_a.primitive == hit_b.primitive);
        }
        // Most rays meet something: the comparison is not of misses alone.
        CHECK(hits > rays / 3);
        CHECK(blocked > rays / 4);
        }
    }
}

// World-space meshes of a few triangles: a floor quad and a tilted wall quad (flat: one merged
// index of two parts), a small smooth tent (its own index); a transformed plate and an instance
// of it in the top level; one sphere and a plane.
scene::Scene tiny_meshes() {
    scene::Scene world;
    world.materials.push_back({});
    world.spheres.push_back({"ball", 0, {0.5, 0, 0.25}, 0.75, glm::dmat4(1.0)});
    world.planes.push_back({"wall", 0, {0, 0, -8}, glm::normalize(glm::dvec3(0.1, 0.2, 1)), glm::dmat4(1.0)});
    scene::Mesh floor;
    floor.positions = {{-4, -1.5, -4}, {4, -1.5, -4}, {4, -1.5, 4}, {-4, -1.5, 4}};
    floor.triangles = {{0, 2, 1}, {0, 3, 2}};
    world.meshes.push_back(floor);
    scene::Mesh mirror;
    mirror.positions = {{-3, -1, -3}, {1, -0.5, -3.5}, {1.5, 2.5, -3.2}, {-2.5, 2, -2.7}};
    mirror.triangles = {{0, 1, 2}, {0, 2, 3}};
    world.meshes.push_back(mirror);
    scene::Mesh tent;
    tent.shading = scene::ShadingMode::smooth;
    tent.positions = {{2, -1.5, 1}, {3.5, -1.5, 1}, {3.5, -1.5, 2.5}, {2, -1.5, 2.5}, {2.75, 0.5, 1.75}};
    tent.triangles = {{0, 4, 1}, {1, 4, 2}, {2, 4, 3}, {3, 4, 0}};
    world.meshes.push_back(tent);
    // A transformed plate and an instance of it: top-level meshes of one leaf, tested directly
    // in their object space.
    scene::Mesh plate;
    plate.positions = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
    plate.triangles = {{0, 2, 1}, {0, 3, 2}};
    plate.transform = glm::rotate(glm::translate(glm::dmat4(1.0), glm::dvec3(-2, 0.5, 1.5)), 0.9,
                                  glm::normalize(glm::dvec3(1, 0.3, -0.5)));
    plate.transform = glm::scale(plate.transform, glm::dvec3(1.2, 1, 0.7));
    world.meshes.push_back(plate);
    scene::MeshInstance copy;
    copy.base_mesh = 3;
    copy.transform = glm::scale(glm::translate(glm::dmat4(1.0), glm::dvec3(1.5, 1.5, -1.5)), glm::dvec3(0.8, 1, 1.5));
    world.mesh_instances.push_back(copy);
    return world;
}

TEST_CASE_TEMPLATE("SceneGeometry: tiny world-space meshes tested without their index find what the index finds", Real,
                   float, double) {
    using Geometry = prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>>;
    using Vec3 = prism::Vec3<Real>;
    const scene::Scene direct_world = tiny_meshes();
    // The world meshes through their indices' traversal too.
    const Geometry direct(direct_world), indexed(past_direct_limit(direct_world, 8));
    REQUIRE(direct.merged_mesh_count() == 3);
    REQUIRE(direct.instance_count() == 6);

    std::mt19937 random(13);
    std::uniform_real_distribution<double> uniform(-1, 1);
    const auto unit = [&] { return random_unit(random); };
    // Targets on the meshes: a vertex, a point on an edge (the quads' shared diagonals, where
    // two triangles tie), or inside a triangle.
    std::vector<std::pair<const scene::Mesh*, glm::dmat4>> meshes;
    for (const auto& mesh : direct_world.meshes) meshes.push_back({&mesh, mesh.transform});
    meshes.push_back({&direct_world.meshes[3], direct_world.mesh_instances[0].transform});
    const auto target = [&](int i) {
        // Not a structured binding: clang 14 cannot capture one in the lambda below.
        const auto& placed = meshes[std::size_t(i) % meshes.size()];
        const scene::Mesh& mesh = *placed.first;
        const glm::dmat4& transform = placed.second;
        const auto& face = mesh.triangles[std::size_t(i / 3) % mesh.triangles.size()];
        const double a = 0.5 * (1 + uniform(random)), b = 0.5 * (1 + uniform(random));
        const auto world = [&](std::uint32_t v) { return glm::dvec3(transform * glm::dvec4(mesh.positions[v], 1.0)); };
        const glm::dvec3 p0 = world(face[0]), p1 = world(face[1]), p2 = world(face[2]);
        switch (i % 4) {
            case 0: return p1;
            case 1: return p0 + a * (p2 - p0);  // the quads' diagonal
            case 2: return p0 + a * (p1 - p0);
            default: return p0 + a * (1 - b) * (p1 - p0) + a * b * (p2 - p0);
        }
    };
    const prism::BackfaceCulling cullings[] = {prism::BackfaceCulling::none, prism::BackfaceCulling::triangles,
                                               prism::BackfaceCulling::all};
    std::size_t hits = 0, mesh_hits = 0, top_mesh_hits = 0, blocked = 0, rays = 0;
    for (int i = 0; i < 120000; ++i) {
        glm::dvec3 origin, direction;
        switch (i % 5) {
            case 0:  // anywhere
                origin = 6.0 * glm::dvec3(uniform(random), uniform(random), uniform(random));
                direction = unit();
                break;
            case 1:
            case 2: {  // through a vertex, an edge or a face, some grazing by 1e-6
                const glm::dvec3 point = target(i / 5);
                origin = point + (0.5 + 5 * std::abs(uniform(random))) * unit();
                direction = glm::normalize(point - origin);
                if (i % 10 == 2) direction = glm::normalize(direction + 1e-6 * unit());
                break;
            }
            case 3: {  // from the floor's plane or one ulp above or below it, some level with it
                origin = glm::dvec3(5 * uniform(random), -1.5, 5 * uniform(random));
                direction = unit();
                if (i % 15 == 3) direction.y = 0.0;
                if (i % 15 == 8) direction.y = -0.0;
                break;
            }
            default: {  // along the box faces of the floor and the tent, within a few ulps
                origin = glm::dvec3(6 * uniform(random), 2 * uniform(random), 6 * uniform(random));
                const double faces[] = {-4, 4, 2, 3.5};
                origin[i % 2 == 0 ? 0 : 2] = faces[std::size_t(i / 5) % 4];
                direction = unit();
                direction[i % 2 == 0 ? 0 : 2] = (i / 7) % 3 == 0 ? 0.0 : ((i / 7) % 3 == 1 ? -0.0 : direction[i % 2 == 0 ? 0 : 2]);
            }
        }
        prism::Ray<Real> ray{Vec3(origin), Vec3(direction), Real(0), Real(40)};
        if (i % 5 == 3) {
            const int step = (i / 5) % 3 - 1;  // the plane itself, or one representable value off
            if (step > 0) ray.origin.y = std::nextafter(ray.origin.y, Real(1));
            if (step < 0) ray.origin.y = std::nextafter(ray.origin.y, Real(-2));
        }
        if (i % 5 == 4 && (i / 3) % 2 == 0) {
            const int axis = i % 2 == 0 ? 0 : 2;
            ray.origin[axis] = std::nextafter(ray.origin[axis], (i / 11) % 2 == 0 ? Real(10) : Real(-10));
        }
        if (i % 3 == 0) ray.t_max = Real(6 * std::abs(uniform(random)));
        if (i % 7 == 0 && i % 5 == 1) ray.t_max = Real(glm::length(target(i / 5) - origin));  // ending on a mesh
        for (const prism::BackfaceCulling culling : cullings) {
            CAPTURE(i);
            CAPTURE(int(culling));
            ++rays;
            prism::Ray<Real> a = ray, b = ray;
            prism::Hit<Real> hit_a, hit_b;
            const auto closest = [&](const Geometry& geometry, prism::Ray<Real>& r, prism::Hit<Real>& hit) {
                switch (culling) {
                    case prism::BackfaceCulling::none: return prism::closest_hit(geometry, r, hit);
                    case prism::BackfaceCulling::triangles:
                        return prism::closest_hit(geometry, r, hit, prism::BackfaceCulling::triangles);
                    default: return prism::closest_hit(geometry, r, hit, prism::BackfaceCulling::all);
                }
            };
            const bool found_a = closest(direct, a, hit_a), found_b = closest(indexed, b, hit_b);
            REQUIRE(found_a == found_b);
            if (culling == prism::BackfaceCulling::none) CHECK(prism::blocked(direct, ray) == prism::blocked(indexed, ray));
            if (!found_a) continue;
            ++hits;
            blocked += prism::blocked(direct, ray);
            CHECK(same_bits(hit_a.t, hit_b.t));
            CHECK(same_bits(a.t_max, b.t_max));
            CHECK(same_bits(hit_a.b1, hit_b.b1));
            CHECK(same_bits(hit_a.b2, hit_b.b2));
            const auto plane_or_object = [](const Geometry& geometry, std::uint32_t object) {
                return object >= geometry.instance_count() ? 1000 + (object - geometry.instance_count()) : std::size_t(object);
            };
            CHECK(plane_or_object(direct, hit_a.object) == plane_or_object(indexed, hit_b.object));
            CHECK(hit_a.primitive == hit_b.primitive);
            mesh_hits += hit_a.object < 5;
            top_mesh_hits += hit_a.object == 3 || hit_a.object == 4;
        }
    }
    CHECK(hits > rays / 3);
    CHECK(mesh_hits > rays / 5);
    CHECK(top_mesh_hits > rays / 20);
    CHECK(blocked > rays / 4);
}

TEST_CASE_TEMPLATE("SceneGeometry: planes tested eight at a time find what one after another finds", Real, float, double) {
    using Geometry = prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>>;
    using Vec3 = prism::Vec3<Real>;
    std::mt19937 random(17);
    std::uniform_real_distribution<double> uniform(-1, 1);
    const auto unit = [&] { return random_unit(random); };
    // Eleven planes (a full block of eight and three more): a room's axis-aligned walls, two of
    // them at the same place facing opposite ways (ties), and tilted ones.
    scene::Scene world;
    world.materials.push_back({});
    const glm::dvec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int i = 0; i < 6; ++i)
        world.planes.push_back({"wall", 0, (i % 2 == 0 ? -3.0 : 3.0) * axes[i / 2], (i % 2 == 0 ? 1.0 : -1.0) * axes[i / 2],
                                glm::dmat4(1.0)});
    world.planes.push_back({"twin", 0, {0, -3, 0}, {0, -1, 0}, glm::dmat4(1.0)});
    for (int i = 0; i < 4; ++i) world.planes.push_back({"tilted", 0, 2.0 * unit(), unit(), glm::dmat4(1.0)});
    std::vector<prism::PlaneShape<Real>> planes;
    for (const auto& plane : world.planes) planes.push_back({Vec3(plane.point), Vec3(glm::normalize(plane.normal))});
    const Geometry geometry(world);
    REQUIRE(geometry.instance_count() == 0);

    std::size_t hits = 0, rays = 0;
    for (int i = 0; i < 100000; ++i) {
        prism::Ray<Real> ray{Vec3(4.0 * glm::dvec3(uniform(random), uniform(random), uniform(random))), Vec3(unit()), Real(0),
                             prism::infinity<Real>};
        if (i % 4 == 1) ray.t_max = Real(4 * std::abs(uniform(random)));
        if (i % 4 == 2) ray.origin.y = Real(-3);  // on the twin walls
        if (i % 8 == 3) ray.direction.x = Real(0);  // parallel to two walls
        if (i % 16 == 5) ray.t_min = Real(-1);
        for (const bool cull : {false, true}) {
            ++rays;
            // The loop intersect_planes replaced: each plane's own test, in order.
            prism::Ray<Real> expected_ray = ray;
            bool expected = false;
            std::uint32_t expected_plane = 0;
            for (std::size_t p = 0; p < planes.size(); ++p) {
                Real t;
                if (!planes[p].intersect(expected_ray, expected_ray.t_min, expected_ray.t_max, t)) continue;
                if (cull && glm::dot(expected_ray.direction, planes[p].normal) > 0) continue;
                expected_ray.t_max = t;
                expected_plane = std::uint32_t(p);
                expected = true;
            }
            prism::Ray<Real> found_ray = ray;
            prism::Hit<Real> hit;
            const bool found = cull ? prism::closest_hit(geometry, found_ray, hit, prism::BackfaceCulling::all)
                                    : prism::closest_hit(geometry, found_ray, hit);
            REQUIRE(found == expected);
            CHECK(same_bits(found_ray.t_max, expected_ray.t_max));
            if (found) {
                ++hits;
                CHECK(same_bits(hit.t, expected_ray.t_max));
                CHECK(hit.object == expected_plane);
            }
        }
        bool blocked = false;
        for (const auto& plane : planes) {
            Real t;
            blocked |= plane.intersect(ray, ray.t_min, ray.t_max, t) && t < ray.t_max;
        }
        CHECK(prism::blocked(geometry, ray) == blocked);
    }
    CHECK(hits > rays / 2);
}

TEST_CASE_TEMPLATE("Blinn-Phong: the power is left out only where the sum is the same without it", Real, float, double) {
    using Vec3 = prism::Vec3<Real>;
    std::mt19937 random(11);
    std::uniform_real_distribution<double> uniform(0, 1);
    const Real power_bound = std::ldexp(Real(1), -prism::Material<Real>::specular_negligible_log2);
    for (const double exponent : {0.5, 1.0, 10.0, 100.0, 1000.0, 1e6}) {
        CAPTURE(exponent);
        scene::Material description;
        description.phong_exponent = exponent;
        prism::Material<Real> material(description);
        const Real below = material.phong_negligible_below;
        REQUIRE(below > 0);
        REQUIRE(below < 1);
        // Up to the threshold the power is at most 2^-K, the bound the shortcut relies on.
        CHECK(std::pow(below, material.phong_exponent) <= power_bound);
        // A cosine of 1 always takes the power; so does a zero diffuse term under a specular one.
        material.specular = Vec3(1);
        CHECK_FALSE(prism::blinn_phong_power_negligible(material, Real(1), Vec3(1)));
        CHECK_FALSE(prism::blinn_phong_power_negligible(material, below, Vec3(1, 0, 1)));
        CHECK(prism::blinn_phong_power_negligible(material, below, Vec3(1)));
        std::size_t skipped = 0;
        for (int i = 0; i < 200000; ++i) {
            const Real cos_half = Real(2 * uniform(random)) * below;  // half of them past the threshold
            material.specular = Vec3(Real(uniform(random)), Real(uniform(random)), i % 5 == 0 ? Real(0) : Real(uniform(random)));
            const Real cos_light = Real(uniform(random));
            const Vec3 diffuse = Vec3(Real(uniform(random)), Real(uniform(random)), Real(uniform(random))) * cos_light;
            if (!prism::blinn_phong_power_negligible(material, cos_half, diffuse)) continue;
            ++skipped;
            REQUIRE(cos_half <= below);
            const Vec3 with = diffuse + material.specular * std::pow(cos_half, material.phong_exponent);
            const Vec3 without = diffuse + material.specular * Real(0);
            for (int c = 0; c < 3; ++c) CHECK(same_bits(with[c], without[c]));
        }
        CHECK(skipped > 50000);
    }
    // No exponent above 0, no threshold: cos^0 = 1 is never negligible.
    for (const double exponent : {0.0, -2.0, std::nan("")}) {
        scene::Material description;
        description.phong_exponent = exponent;
        const prism::Material<Real> material(description);
        CHECK_FALSE(prism::blinn_phong_power_negligible(material, Real(0), Vec3(1)));
    }
}

TEST_CASE_TEMPLATE("Blinn-Phong: the power of exponent 1 is std::pow's, bit for bit", Real, float, double) {
    // The shortcut returns the cosine itself; std::pow(x, 1) must be x for the images to stay.
    std::mt19937 random(12);
    std::uniform_real_distribution<double> uniform(0, 1);
    const auto check = [](Real x) {
        CAPTURE(x);
        CHECK(same_bits(prism::blinn_phong_power(x, Real(1)), Real(std::pow(x, Real(1)))));
        // Other exponents are std::pow itself.
        for (const Real exponent : {Real(0), Real(0.5), Real(3), Real(10), Real(100), Real(300)})
            CHECK(same_bits(prism::blinn_phong_power(x, exponent), Real(std::pow(x, exponent))));
    };
    for (const Real x : {Real(0), Real(1), std::nextafter(Real(1), Real(2)), std::nextafter(Real(1), Real(0)),
                         std::numeric_limits<Real>::denorm_min(), std::numeric_limits<Real>::min(), Real(1e-30)})
        check(x);
    for (int i = 0; i < 100000; ++i) check(Real(uniform(random)));
    // A NaN cosine (a NaN half vector) stays NaN, as std::pow leaves it.
    CHECK(std::isnan(prism::blinn_phong_power(std::numeric_limits<Real>::quiet_NaN(), Real(1))));
}

namespace {

// hw1 ocornellbox's room: five walls of two triangles each, all flat, merged into one
// world-space index of ten triangles, which the build splits into a root of two leaves; two
// spheres inside make the top level direct.
scene::Scene two_leaf_room() {
    scene::Scene world;
    world.materials.push_back({});
    world.spheres.push_back({"ball", 0, {5, -6, 1}, 4.0, glm::dmat4(1.0)});
    world.spheres.push_back({"mirror", 0, {-5, -6, -5}, 4.0, glm::dmat4(1.0)});
    const std::vector<glm::dvec3> corners = {{-10, -10, 10}, {10, -10, 10}, {10, 10, 10}, {-10, 10, 10},
                                             {-10, -10, -10}, {10, -10, -10}, {10, 10, -10}, {-10, 10, -10}};
    const std::vector<std::array<std::uint32_t, 3>> walls = {{0, 1, 5}, {5, 4, 0}, {4, 5, 6}, {6, 7, 4}, {6, 2, 3},
                                           {3, 7, 6}, {7, 3, 0}, {7, 0, 4}, {1, 2, 6}, {1, 6, 5}};
    for (std::size_t wall = 0; wall < walls.size(); wall += 2) {
        scene::Mesh mesh;
        mesh.positions = corners;
        mesh.triangles = {walls[wall], walls[wall + 1]};
        world.meshes.push_back(mesh);
    }
    return world;
}

}  // namespace

TEST_CASE_TEMPLATE("SceneGeometry: a world-space index whose root has two leaves, tested leaf by leaf, finds what the index finds",
                   Real, float, double) {
    using Geometry = prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>>;
    using Mesh = prism::TriangleMesh<Real, prism::WideBvh<prism::Watertight, 8>>;
    using Vec3 = prism::Vec3<Real>;
    const scene::Scene room = two_leaf_room();
    // The shape this test is about: the ten triangles as one index, a root of two leaves.
    std::vector<const scene::Mesh*> parts;
    for (const auto& mesh : room.meshes) parts.push_back(&mesh);
    const Mesh merged{std::span<const scene::Mesh* const>(parts)};
    const auto leaves = merged.root_leaves();
    REQUIRE(leaves);
    REQUIRE(leaves->count == 2);
    CHECK(!merged.single_leaf());
    const Geometry direct(room), indexed(past_direct_limit(room, 8));
    REQUIRE(direct.merged_mesh_count() == 5);

    std::mt19937 random(29);
    std::uniform_real_distribution<double> uniform(-1, 1);
    // Points on the room's edges (where two walls, often in different leaves, meet: the rays
    // whose two hits tie), on its corners, and inside its walls.
    const auto on_room = [&](int i) {
        glm::dvec3 p(10 * uniform(random), 10 * uniform(random), 10 * uniform(random));
        const int a = i % 3, b = (i + 1) % 3;
        switch (i % 4) {
            case 0: p[a] = (i / 4) % 2 == 0 ? -10 : 10; p[b] = (i / 8) % 2 == 0 ? -10 : 10; break;  // an edge
            case 1: p = {(i / 4) % 2 == 0 ? -10 : 10, -10, (i / 8) % 2 == 0 ? -10 : 10}; break;  // a corner
            default: p[a] = (i / 4) % 2 == 0 ? -10 : 10;  // a wall
        }
        return p;
    };
    const prism::BackfaceCulling cullings[] = {prism::BackfaceCulling::none, prism::BackfaceCulling::triangles};
    std::size_t rays = 0, hits = 0, wall_hits = 0, blocked = 0, edge_rays = 0, lefts = 0;
    // The same rays in batches (a row's camera rays, a row's shadow rays to one light), which
    // the direct form tests a ray in each lane, leaf after leaf: each ray's answer must be the
    // one it gets alone, for batches of 1 to 16 rays with gaps in the active mask.
    REQUIRE(direct.route() == prism::BatchRoute::leaf_lanes);
    struct Batch {
        std::vector<prism::Ray<Real>> rays, alone;
        std::vector<prism::Hit<Real>> hits;
        std::vector<int> found, occluded;
    };
    Batch batches[2];
    std::size_t batched = 0, batch_hits = 0;
    const auto check_batch = [&](Batch& batch, prism::BackfaceCulling culling, std::uint32_t active) {
        const int count = int(batch.rays.size());
        std::vector<prism::Ray<Real>> rays = batch.rays;
        std::vector<prism::Hit<Real>> got(static_cast<std::size_t>(count));
        for (auto& hit : got) hit.object = 12345;  // left alone where a ray finds nothing
        const std::uint32_t found = direct.intersect(prism::RayBatch<Real>{rays.data(), count, active, culling}, got.data());
        std::uint32_t occluded = direct.occluded(prism::RayBatch<Real>{batch.rays.data(), count, active, culling});
        CHECK((found & ~active) == 0);
        CHECK((occluded & ~active) == 0);
        for (int k = 0; k < count; ++k) {
            CAPTURE(k);
            const std::size_t j = std::size_t(k);
            if (!((active >> k) & 1)) {
                CHECK(same_bits(rays[j].t_max, batch.rays[j].t_max));
                CHECK(got[j].object == 12345u);
                continue;
            }
            ++batched;
            CHECK(int((occluded >> k) & 1) == batch.occluded[j]);
            REQUIRE(int((found >> k) & 1) == batch.found[j]);
            CHECK(same_bits(rays[j].t_max, batch.alone[j].t_max));
            if (!batch.found[j]) {
                CHECK(got[j].object == 12345u);
                continue;
            }
            ++batch_hits;
            CHECK(same_bits(got[j].t, batch.hits[j].t));
            CHECK(same_bits(got[j].b1, batch.hits[j].b1));
            CHECK(same_bits(got[j].b2, batch.hits[j].b2));
            CHECK(got[j].object == batch.hits[j].object);
            CHECK(got[j].primitive == batch.hits[j].primitive);
        }
        batch = {};
    };
    for (int i = 0; i < 100000; ++i) {
        glm::dvec3 origin, direction;
        switch (i % 4) {
            case 0:  // from anywhere, inside the room or out (its front is open)
                origin = 14.0 * glm::dvec3(uniform(random), uniform(random), uniform(random));
                direction = random_unit(random);
                break;
            case 1: {  // from outside, at an edge, a corner or a wall: half from the camera's side
                // (through the open front), half from every side (the leaves' boxes entered at
                // different distances, so that the traversal's order decides the ties)
                const glm::dvec3 point = on_room(i / 4);
                origin = (i / 4) % 2 == 0 ? glm::dvec3(3 * uniform(random), 3 * uniform(random), 20 + 5 * std::abs(uniform(random)))
                                          : (25 + 5 * std::abs(uniform(random))) * random_unit(random);
                direction = glm::normalize(point - origin);
                ++edge_rays;
                break;
            }
            case 2: {  // from inside towards an edge, a corner or a wall, some grazing
                const glm::dvec3 point = on_room(i / 4);
                origin = 9.0 * glm::dvec3(uniform(random), uniform(random), uniform(random));
                direction = glm::normalize(point - origin);
                if (i % 8 == 6) direction = glm::normalize(direction + 1e-6 * random_unit(random));
                ++edge_rays;
                break;
            }
            default: {  // from a wall, as the renderer's shadow and reflected rays leave
                origin = on_room(4 * (i / 4) + 2 + (i / 4) % 2);
                direction = random_unit(random);
            }
        }
        prism::Ray<Real> ray{Vec3(origin), Vec3(direction), Real(i % 4 == 3 ? 1e-3 : 0), Real(60)};
        if (i % 3 == 0) ray.t_max = Real(30 * std::abs(uniform(random)));
        if (i % 16 == 5) ray.direction[std::size_t(i / 16) % 3] = Real(i % 32 == 5 ? 0 : -0.0);  // along a face
        // The leaves' boxes in one pass (left_by) say what leaves_box says of each; of a ray
        // that starts behind its origin (t_min < 0), nothing.
        prism::Ray<Real> probe = ray;
        if (i % 64 == 7) probe.t_min = Real(-1);
        std::uint32_t left = 0;
        for (int leaf = 0; leaf < leaves->count; ++leaf)
            left |= std::uint32_t(prism::leaves_box(leaves->leaf[std::size_t(leaf)].box, probe)) << leaf;
        CHECK(leaves->left_by(probe) == left);
        lefts += left != 0;
        for (const prism::BackfaceCulling culling : cullings) {
            CAPTURE(i);
            CAPTURE(int(culling));
            ++rays;
            prism::Ray<Real> a = ray, b = ray;
            prism::Hit<Real> hit_a, hit_b;
            // As a camera ray (depth 0) under `culling`.
            const bool found_a = prism::closest_hit(direct, a, hit_a, culling);
            const bool found_b = prism::closest_hit(indexed, b, hit_b, culling);
            REQUIRE(found_a == found_b);
            const bool occluded = prism::blocked(direct, ray);
            CHECK(occluded == prism::blocked(indexed, ray));
            Batch& batch = batches[culling == prism::BackfaceCulling::none ? 0 : 1];
            batch.rays.push_back(ray);
            batch.alone.push_back(a);
            batch.hits.push_back(hit_a);
            batch.found.push_back(found_a);
            batch.occluded.push_back(occluded);
            if (int(batch.rays.size()) == 1 + (i / 2) % 16) {
                // Every ray active, or every third left out.
                const int count = int(batch.rays.size());
                std::uint32_t active = count == 32 ? ~0u : (std::uint32_t(1) << count) - 1;
                if ((i / 32) % 2 == 1) active &= ~0x49249249u;
                check_batch(batch, culling, active == 0 ? 1u : active);
            }
            if (!found_a) continue;
            ++hits;
            blocked += occluded;
            check_same_hit(a, hit_a, b, hit_b);
            wall_hits += hit_a.object < 5;
        }
    }
    CHECK(edge_rays > 40000);
    CHECK(batched > rays * 2 / 3);
    CHECK(batch_hits > batched / 2);
    CHECK(lefts > 10000);  // the boxes' test skipped leaves for many rays
    CHECK(hits > rays / 2);
    CHECK(wall_hits > rays / 3);
    CHECK(blocked > rays / 3);
}

// A scene with a path-traced camera builds its world-space room (at most 64 triangles) with a
// wall to a leaf (SceneIndex::world_max_leaf_size): another tree over the same triangles, so
// every ray from the walls must find the same hit (the same distance, triangle and
// barycentrics) and the same shadow-ray answer as through the builder's own leaves, the ray
// tracer's shape of the same room; the ray tracer's scenes and larger rooms keep that shape.
TEST_CASE_TEMPLATE("SceneGeometry: a path-traced room, a wall to a leaf, finds what the builder's leaves find", Real, float,
                   double) {
    using Geometry = prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>>;
    using Vec3 = prism::Vec3<Real>;
    scene::Scene ray_traced = two_leaf_room();
    ray_traced.cameras.push_back({});
    scene::Scene path_traced = ray_traced;
    path_traced.cameras.push_back({});
    path_traced.cameras[1].renderer.path_tracing = true;
    CHECK(Geometry::world_max_leaf_size(ray_traced) == 0);
    REQUIRE(Geometry::world_max_leaf_size(path_traced) == 2);
    scene::Scene hall = path_traced;  // 10 + 56 triangles: past a room
    hall.meshes.push_back(hall.meshes[0]);
    for (int i = 0; i < 27; ++i) hall.meshes.back().triangles.push_back(hall.meshes[0].triangles[std::size_t(i % 2)]);
    REQUIRE(hall.meshes.back().triangles.size() == 29);
    hall.meshes.push_back(hall.meshes.back());
    CHECK(Geometry::world_max_leaf_size(hall) == 0);
    hall.meshes.back().triangles.resize(25);  // 64
    CHECK(Geometry::world_max_leaf_size(hall) == 2);

    const Geometry builders(ray_traced), walls(path_traced);
    REQUIRE(walls.merged_mesh_count() == 5);
    CHECK(builders.route() == prism::BatchRoute::leaf_lanes);  // a root of two leaves, tested directly
    CHECK(walls.route() != prism::BatchRoute::leaf_lanes);     // five leaves: through the index

    std::mt19937 random(32);
    std::uniform_real_distribution<double> uniform(-1, 1);
    std::size_t rays = 0, hits = 0, blocked = 0;
    for (int i = 0; i < 40000; ++i) {
        // From a point of a wall (or just inside the room), every direction: the path tracer's
        // bounces and shadow rays.
        glm::dvec3 origin(9.9 * uniform(random), 9.9 * uniform(random), 9.9 * uniform(random));
        if (i % 4 != 3) origin[std::size_t(i % 3)] = (i / 3) % 2 == 0 ? -10 : 10;
        const glm::dvec3 direction = random_unit(random);
        prism::Ray<Real> ray{Vec3(origin), Vec3(direction), Real(i % 4 == 3 ? 0 : 1e-3), Real(60)};
        if (i % 2 == 0) ray.t_max = Real(25 * std::abs(uniform(random)));  // a shadow ray's length
        for (const prism::BackfaceCulling culling : {prism::BackfaceCulling::none, prism::BackfaceCulling::triangles}) {
            CAPTURE(i);
            ++rays;
            prism::Ray<Real> a = ray, b = ray;
            prism::Hit<Real> hit_a, hit_b;
            const bool found = prism::closest_hit(builders, a, hit_a, culling);
            REQUIRE(found == prism::closest_hit(walls, b, hit_b, culling));
            const bool occluded = prism::blocked(builders, ray);
            CHECK(occluded == prism::blocked(walls, ray));
            blocked += occluded;
            if (!found) continue;
            ++hits;
            check_same_hit(a, hit_a, b, hit_b);
        }
    }
    CHECK(hits > rays / 3);  // the room's front is open
    CHECK(blocked > rays / 4);
}

// Shadow rays tested several at a time (a point's rays to its lights, a batch with gaps; a row's
// rays, a ray in each lane): every ray of a batch, for any set of active rays, gets what it
// gets alone, in the
// scenes above (direct spheres of each kind, planes, one-leaf world meshes, transformed
// top-level plates), from points on and near the surfaces and in open space.
TEST_CASE_TEMPLATE("SceneGeometry: shadow rays tested several at a time get what each gets alone", Real, float, double) {
    using Geometry = prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>>;
    for (int kind = 0; kind < 3; ++kind) {
        CAPTURE(kind);
        const scene::Scene world = kind == 2 ? tiny_meshes() : few_spheres(kind == 1, kind == 1);
        const Geometry geometry(world);
        REQUIRE(geometry.route() != prism::BatchRoute::index_lanes);

        std::mt19937 random(11);
        std::uniform_real_distribution<double> uniform(-1, 1), fraction(0, 1);
        const std::array<glm::dvec3, 8> lights = {glm::dvec3(0, 4, 0), {3, 3, 2},     {-3, 2, -2},  {0.5, 1.2, 0.1},
                                                  {4.5, -1, 3},        {-4, 3.5, 3},  {1, -1.2, -3}, {0, 0, 5}};
        std::size_t blocked = 0, rays = 0;
        for (int batch = 0; batch < 6000; ++batch) {
            // A point on or near a sphere, on or near the floor's height, or in open space.
            glm::dvec3 from;
            if (batch % 3 == 0) {
                const scene::Sphere& sphere = world.spheres[std::size_t(batch / 3) % world.spheres.size()];
                from = glm::dvec3(sphere.transform * glm::dvec4(sphere.center + sphere.radius * random_unit(random), 1.0));
                from += 1e-4 * random_unit(random);
            } else if (batch % 3 == 1) {
                from = {4 * uniform(random), -1.5 + 1e-4 * uniform(random), 4 * uniform(random)};
            } else {
                from = 5.0 * glm::dvec3(uniform(random), uniform(random), uniform(random));
            }
            std::array<prism::Ray<Real>, 8> shadows;
            std::uint32_t lanes = 0;
            for (std::size_t i = 0; i < lights.size(); ++i) {
                if (fraction(random) < 0.25) continue;
                const glm::dvec3 to_light = lights[i] - from;
                prism::Ray<Real> ray{prism::Vec3<Real>(from), prism::Vec3<Real>(glm::normalize(to_light)), Real(0),
                                     Real(glm::length(to_light))};
                if (batch % 7 == 0) ray.direction = prism::Vec3<Real>(random_unit(random));
                if (batch % 11 == 0) ray.t_min = Real(1e-3);
                shadows[i] = ray;
                lanes |= std::uint32_t(1) << i;
            }
            std::uint32_t expected = 0;
            for (std::uint32_t rest = lanes; rest != 0; rest &= rest - 1) {
                const int lane = std::countr_zero(rest);
                if (prism::blocked(geometry, shadows[std::size_t(lane)])) expected |= std::uint32_t(1) << lane;
                ++rays;
            }
            CHECK(geometry.occluded(prism::RayBatch<Real>{shadows.data(), 8, lanes}) == expected);
            // The lit rays side by side (a row's shadow rays to one light): the same answers.
            std::array<prism::Ray<Real>, 8> packed;
            int packed_count = 0;
            std::uint32_t packed_expected = 0;
            for (std::uint32_t rest = lanes; rest != 0; rest &= rest - 1) {
                const int lane = std::countr_zero(rest);
                if ((expected >> lane) & 1) packed_expected |= std::uint32_t(1) << packed_count;
                packed[std::size_t(packed_count++)] = shadows[std::size_t(lane)];
            }
            CHECK(geometry.occluded(prism::RayBatch<Real>::all(packed.data(), packed_count)) == packed_expected);
            blocked += std::size_t(std::popcount(expected));
        }
        // Both answers are common: the comparison is not of misses (or of hits) alone.
        CHECK(blocked > rays / 10);
        CHECK(blocked < rays * 9 / 10);
    }
}

// Camera rays tested several at a time (a batch through SceneGeometry::intersect: the world
// meshes' leaves and the direct spheres with a ray in each lane): every ray of a batch, of any
// length up to a row's 16, gets the hit it gets alone, to the bit (t, object, primitive,
// barycentrics, the lowered t_max), under each culling rule, in the scenes above: direct
// spheres of every map (plain, translated, ellipsoids), a floor of two triangles and planes
// side by side; merged flat quads, a smooth tent and transformed plates through intersect's
// own path. The rays fan out from a camera, as a
// row's do, aim through the spheres' surfaces (grazing ones included) and the quads' shared
// diagonals, or go anywhere.
TEST_CASE_TEMPLATE("SceneGeometry: camera rays tested several at a time get what each gets alone", Real, float, double) {
    using Geometry = prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>>;
    using prism::BackfaceCulling;
    for (int kind = 0; kind < 5; ++kind) {
        CAPTURE(kind);
        // Kind 4: spheres and the floor without the plane, where the batches skip the planes' pass.
        scene::Scene world = kind == 3 ? tiny_meshes() : few_spheres(kind >= 1, kind == 2);
        if (kind == 4) world.planes.clear();
        const Geometry geometry(world);
        // Side by side where the top level holds spheres alone; the transformed plates of
        // tiny_meshes keep the one-ray path, which the batch must then give too.
        REQUIRE((geometry.route() == prism::BatchRoute::leaf_lanes) == (kind != 3));

        std::mt19937 random(23);
        std::uniform_real_distribution<double> uniform(-1, 1), fraction(0, 1);
        const auto intersect = [&](BackfaceCulling culling, prism::Ray<Real>& ray, prism::Hit<Real>& hit) {
            switch (culling) {
                case BackfaceCulling::none: return prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::none);
                case BackfaceCulling::triangles: return prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::triangles);
                case BackfaceCulling::all: break;
            }
            return prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::all);
        };
        const auto intersect_each = [&](BackfaceCulling culling, prism::Ray<Real>* rays, prism::Hit<Real>* hits, int count) {
            return geometry.intersect(prism::RayBatch<Real>::all(rays, count, culling), hits);
        };
        std::size_t rays_tested = 0, hits_found = 0;
        std::array<std::size_t, 3> kinds_hit{};  // spheres, triangles, planes
        for (int batch = 0; batch < 4000; ++batch) {
            const BackfaceCulling culling = BackfaceCulling(batch % 3);
            const int count = 1 + int(fraction(random) * 16);
            const glm::dvec3 camera = glm::dvec3(0, 1, 9) + 2.0 * glm::dvec3(uniform(random), uniform(random), uniform(random));
            std::array<prism::Ray<Real>, 16> rays;
            for (int i = 0; i < count; ++i) {
                glm::dvec3 origin = camera, direction;
                if (batch % 4 == 0) {
                    // A row's fan of directions toward the scene.
                    direction = glm::normalize(glm::dvec3(-0.6 + 1.2 * (i + 0.5) / count, 0.3 * uniform(random) - 0.25, -1));
                } else if (batch % 4 == 1) {
                    const scene::Sphere& sphere = world.spheres[std::size_t(batch + i) % world.spheres.size()];
                    const glm::dvec3 target = glm::dvec3(sphere.transform * glm::dvec4(sphere.center + sphere.radius * random_unit(random), 1.0));
                    direction = glm::normalize(target - origin);
                    if (i % 2 == 1) direction = glm::normalize(direction + 1e-4 * random_unit(random));
                } else if (batch % 4 == 2) {
                    // Through the floor's diagonal (x = z at height -1.5), where its two triangles meet.
                    const double s = 3 * uniform(random);
                    direction = glm::normalize(glm::dvec3(s, -1.5, s) - origin);
                } else {
                    origin = 5.0 * glm::dvec3(uniform(random), uniform(random), uniform(random));
                    direction = random_unit(random);
                }
                rays[std::size_t(i)] = prism::Ray<Real>{prism::Vec3<Real>(origin), prism::Vec3<Real>(direction), Real(0), Real(60)};
                if (batch % 5 == 0) rays[std::size_t(i)].t_max = Real(12 * fraction(random));
                if (batch % 7 == 0) rays[std::size_t(i)].t_min = Real(1e-3);
            }
            std::array<prism::Ray<Real>, 16> each = rays;
            std::array<prism::Ray<Real>, 16> rays_before = rays;  // as the rays were before any query
            // The same rays as shadow rays, as one batch.
            std::uint32_t blocked = 0;
            for (int i = 0; i < count; ++i)
                if (prism::blocked(geometry, rays[std::size_t(i)])) blocked |= std::uint32_t(1) << i;
            CHECK(geometry.occluded(prism::RayBatch<Real>::all(rays.data(), count)) == blocked);
            std::array<prism::Hit<Real>, 16> hits, each_hits;
            const std::uint32_t found = intersect_each(culling, each.data(), each_hits.data(), count);
            for (int i = 0; i < count; ++i) {
                CAPTURE(i);
                const bool alone = intersect(culling, rays[std::size_t(i)], hits[std::size_t(i)]);
                ++rays_tested;
                REQUIRE(alone == bool((found >> i) & 1));
                const prism::Hit<Real>& a = hits[std::size_t(i)];
                const prism::Hit<Real>& b = each_hits[std::size_t(i)];
                CHECK(same_bits(rays[std::size_t(i)].t_max, each[std::size_t(i)].t_max));
                CHECK(same_bits(a.t, b.t));
                CHECK(a.object == b.object);
                CHECK(a.primitive == b.primitive);
                CHECK(same_bits(a.b1, b.b1));
                CHECK(same_bits(a.b2, b.b2));
                if (!alone) continue;
                ++hits_found;
                const std::size_t kind_hit = a.object >= geometry.instance_count() ? 2 : a.object < world.meshes.size() + world.mesh_instances.size() ? 1 : 0;
                ++kinds_hit[kind_hit];
            }
            CHECK(found < (std::uint32_t(1) << count));
            // The same batch with a random active mask, gaps included: the active rays get what
            // they get alone, the others are left as they were (t_max and hit untouched).
            const std::uint32_t mask = std::uint32_t(random()) & ((std::uint32_t(1) << count) - 1);
            std::array<prism::Ray<Real>, 16> masked = rays_before;
            std::array<prism::Hit<Real>, 16> masked_hits;
            for (auto& hit : masked_hits) hit.object = 12345;
            const std::uint32_t masked_found = geometry.intersect(prism::RayBatch<Real>{masked.data(), count, mask, culling}, masked_hits.data());
            CHECK(masked_found == (found & mask));
            std::uint32_t masked_blocked_expected = 0;
            for (int i = 0; i < count; ++i) {
                CAPTURE(i);
                const std::size_t k = std::size_t(i);
                if (!((mask >> i) & 1)) {
                    CHECK(same_bits(masked[k].t_max, rays_before[k].t_max));
                    CHECK(masked_hits[k].object == 12345);
                    continue;
                }
                if (prism::blocked(geometry, rays_before[k])) masked_blocked_expected |= std::uint32_t(1) << i;
                CHECK(same_bits(masked[k].t_max, rays[k].t_max));
                if (!((found >> i) & 1)) continue;
                CHECK(same_bits(masked_hits[k].t, hits[k].t));
                CHECK(masked_hits[k].object == hits[k].object);
                CHECK(masked_hits[k].primitive == hits[k].primitive);
            }
            CHECK(geometry.occluded(prism::RayBatch<Real>{rays_before.data(), count, mask}) == masked_blocked_expected);
        }
        // Hits and misses both common, and every kind of surface met.
        CHECK(hits_found > rays_tested / 5);
        CHECK(hits_found < rays_tested * 9 / 10);
        CHECK(kinds_hit[0] > 100);
        if (kind != 4) CHECK(kinds_hit[2] > 100);
        if (kind >= 1) CHECK(kinds_hit[1] > 100);
    }
}

TEST_CASE_TEMPLATE("SceneGeometry: moving spheres and plates in a direct top level find, at each ray's instant, what the index finds",
                   Real, float, double) {
    // Motion blur (the course's MotionBlur translation over the shutter interval) on a plain
    // sphere (its lanes move each ray's origin back by the motion at the ray's instant), on the
    // ellipsoid (a matrix after the shift: ray by ray) and, in one variant, on a transformed
    // plate in the top level. The direct form (a bound around each sweep) must find what the
    // same objects give through the top-level index, one ray at a time and in batches.
    using Geometry = prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>, true>;
    for (const bool plate : {false, true}) {
        CAPTURE(plate);
        scene::Scene world = few_spheres(true);
        world.spheres[0].motion = {0.6, 0.2, -0.9};
        world.spheres[2].motion = {-0.4, 0.5, 0.2};
        if (plate) {
            scene::Mesh moving;
            moving.positions = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
            moving.triangles = {{0, 2, 1}, {0, 3, 2}};
            moving.transform = glm::rotate(glm::translate(glm::dmat4(1.0), glm::dvec3(1.5, -0.5, 2)), 0.6, glm::dvec3(1, 0, 0));
            moving.motion = {0.3, 0.8, 0};
            world.meshes.push_back(moving);
        }
        const Geometry direct(world), indexed(past_direct_limit(world, 5));
        // The direct form (leaf lanes where the top level holds spheres alone) and the index.
        REQUIRE(direct.route() == (plate ? prism::BatchRoute::ray_by_ray : prism::BatchRoute::leaf_lanes));
        REQUIRE(indexed.route() == prism::BatchRoute::index_lanes);

        std::mt19937 random(31);
        std::uniform_real_distribution<double> uniform(-1, 1), fraction(0, 1);
        std::size_t rays_tested = 0, moving_hits = 0;
        for (int batch = 0; batch < 3000; ++batch) {
            const int count = 1 + int(fraction(random) * 16);
            std::array<prism::Ray<Real>, 16> rays;
            for (int i = 0; i < count; ++i) {
                const double time = fraction(random);
                glm::dvec3 origin = 5.0 * glm::dvec3(uniform(random), uniform(random), uniform(random)), direction;
                if ((batch + i) % 2 == 0) {
                    // At a moving object where it is at the ray's instant, through or grazing.
                    const scene::Sphere& sphere = world.spheres[(batch + i) % 4 < 2 ? 0 : 2];
                    const glm::dvec3 target =
                        glm::dvec3(sphere.transform * glm::dvec4(sphere.center + sphere.radius * random_unit(random), 1.0)) +
                        time * sphere.motion;
                    origin = target + (1 + 4 * fraction(random)) * random_unit(random);
                    direction = glm::normalize(target - origin);
                    if (i % 3 == 1) direction = glm::normalize(direction + 1e-4 * random_unit(random));
                } else {
                    direction = random_unit(random);
                }
                rays[std::size_t(i)] = prism::Ray<Real>{prism::Vec3<Real>(origin), prism::Vec3<Real>(direction), Real(0), Real(50)};
                rays[std::size_t(i)].time = Real(time);
                if (batch % 5 == 0) rays[std::size_t(i)].t_max = Real(6 * fraction(random));
            }
            std::array<prism::Ray<Real>, 16> batched = rays;
            std::array<prism::Hit<Real>, 16> batch_hits;
            const std::uint32_t found = direct.intersect(prism::RayBatch<Real>::all(batched.data(), count), batch_hits.data());
            std::uint32_t blocked = 0;
            for (int i = 0; i < count; ++i) {
                CAPTURE(i);
                ++rays_tested;
                prism::Ray<Real> a = rays[std::size_t(i)], b = a;
                prism::Hit<Real> hit_a, hit_b;
                const bool found_a = prism::closest_hit(direct, a, hit_a), found_b = prism::closest_hit(indexed, b, hit_b);
                REQUIRE(found_a == found_b);
                REQUIRE(found_a == bool((found >> i) & 1));
                const bool occluded = prism::blocked(direct, rays[std::size_t(i)]);
                CHECK(occluded == prism::blocked(indexed, rays[std::size_t(i)]));
                blocked |= std::uint32_t(occluded) << i;
                if (!found_a) continue;
                CHECK(same_bits(hit_a.t, hit_b.t));
                CHECK(same_bits(a.t_max, b.t_max));
                CHECK(same_bits(hit_a.t, batch_hits[std::size_t(i)].t));
                CHECK(same_bits(a.t_max, batched[std::size_t(i)].t_max));
                CHECK(hit_a.object == batch_hits[std::size_t(i)].object);
                CHECK(hit_a.primitive == batch_hits[std::size_t(i)].primitive);
                // Planes are numbered after the objects, so past the far spheres in the indexed scene.
                const auto plane_or_object = [](const Geometry& geometry, std::uint32_t object) {
                    return object >= geometry.instance_count() ? 1000 + (object - geometry.instance_count()) : std::size_t(object);
                };
                CHECK(plane_or_object(direct, hit_a.object) == plane_or_object(indexed, hit_b.object));
                CHECK(hit_a.primitive == hit_b.primitive);
                const std::size_t first_sphere = world.meshes.size();
                moving_hits += hit_a.object == first_sphere || hit_a.object == first_sphere + 2 ||
                               (plate && hit_a.object == world.meshes.size() - 1);
            }
            CHECK(direct.occluded(prism::RayBatch<Real>::all(rays.data(), count)) == blocked);
        }
        // The moving objects are met, not only missed.
        CHECK(moving_hits > rays_tested / 5);
    }
}
