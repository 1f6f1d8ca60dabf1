// Shadow rays side by side through an index (WideBvhTree::traverse_any_lanes,
// one batch through SceneGeometry::occluded in scenes with a top-level index): each ray must reach
// exactly the leaves it reaches alone and get the answer occluded gives it alone, whatever rays
// share its lanes. Camera rays side by side (WideBvhTree::traverse_closest_lanes,
// one batch through SceneGeometry::intersect) must get each ray's own hit, ties included.
// And the world-space indices of one or two leaves, tested leaf by leaf in an index scene, must
// give intersect's hits as the exhaustive test gives them.
#include "same_bits.hpp"

#include <prism/accel/accelerator.hpp>
#include <prism/accel/wide_bvh_tree.hpp>
#include <prism/geometry/scene_geometry.hpp>

#include <glm/gtc/matrix_transform.hpp>

#include <doctest/doctest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <utility>
#include <vector>

using prism_test::same_bits;

namespace {

namespace scene = prism::scene;

glm::dvec3 random_unit(std::mt19937& random) {
    std::normal_distribution<double> normal;
    for (;;) {
        const glm::dvec3 v(normal(random), normal(random), normal(random));
        if (glm::length(v) > 1e-6) return glm::normalize(v);
    }
}

// A k x k grid of triangle pairs in the plane y = 0 over [0, k]^2 (x, z), raised by `bump` at
// alternate vertices so that neighbouring triangles are not coplanar.
scene::Mesh bumpy_grid(int k, double bump, std::size_t material) {
    scene::Mesh mesh;
    mesh.material = material;
    for (int z = 0; z <= k; ++z)
        for (int x = 0; x <= k; ++x) mesh.positions.push_back({double(x), ((x + z) % 2) * bump, double(z)});
    const auto at = [k](int x, int z) { return std::uint32_t(z * (k + 1) + x); };
    for (int z = 0; z < k; ++z)
        for (int x = 0; x < k; ++x) {
            mesh.triangles.push_back({at(x, z), at(x, z + 1), at(x + 1, z + 1)});
            mesh.triangles.push_back({at(x, z), at(x + 1, z + 1), at(x + 1, z)});
        }
    return mesh;
}

// A scene with a top-level index: a world-space grid of 288 triangles (flat: merged, its own
// index), a world-space floor of two triangles (smooth: a group of its own, one leaf), a
// transformed grid placed twice more by instances (one of them moving where `moving`), an
// ellipsoid and a sphere, and a plane behind everything.
scene::Scene index_scene(bool moving) {
    scene::Scene world;
    world.materials.push_back({});
    world.meshes.push_back(bumpy_grid(12, 0.15, 0));
    world.meshes.back().transform = glm::dmat4(1.0);
    for (auto& p : world.meshes.back().positions) p = glm::dvec3(p.x - 6, p.y + 0.5, p.z - 6) * 0.5;
    scene::Mesh floor;
    floor.shading = scene::ShadingMode::smooth;
    floor.positions = {{-6, -1, -6}, {6, -1, -6}, {6, -1, 6}, {-6, -1, 6}};
    floor.triangles = {{0, 2, 1}, {0, 3, 2}};
    world.meshes.push_back(floor);
    world.meshes.push_back(bumpy_grid(8, 0.3, 0));
    world.meshes.back().transform = glm::translate(glm::dmat4(1.0), glm::dvec3(-3, 1.5, -1)) *
                                    glm::rotate(glm::dmat4(1.0), 0.7, glm::dvec3(1, 0.3, 0.2)) *
                                    glm::scale(glm::dmat4(1.0), glm::dvec3(0.4));
    world.mesh_instances.push_back({"again", 2, 0, glm::translate(glm::dmat4(1.0), glm::dvec3(4, 0.5, 1)) * world.meshes[2].transform, {}, {}});
    world.mesh_instances.push_back({"moving", 2, 0, glm::translate(glm::dmat4(1.0), glm::dvec3(1, 2.5, 2)) * world.meshes[2].transform, {}, {}});
    if (moving) world.mesh_instances.back().motion = glm::dvec3(0.5, 0, 0.25);
    world.spheres.push_back({"ellipsoid", 0, {0, 0, 0}, 0.8,
                             glm::translate(glm::dmat4(1.0), glm::dvec3(1.5, 0.6, -2)) * glm::scale(glm::dmat4(1.0), glm::dvec3(1, 0.5, 1.5))});
    world.spheres.push_back({"ball", 0, {-2, 0.2, 2.5}, 0.7, glm::dmat4(1.0)});
    world.planes.push_back({"wall", 0, {0, 0, -8}, {0, 0, 1}, glm::dmat4(1.0)});
    return world;
}

// A deterministic per-ray, per-primitive coin: whether a primitive blocks a ray in the tree tests.
bool blocks(std::uint32_t ray, std::uint32_t primitive, std::uint32_t odds) {
    std::uint32_t h = ray * 0x9E3779B1u ^ (primitive + 0x7F4A7C15u) * 0x85EBCA77u;
    h ^= h >> 15;
    h *= 0x2C1B3C6Du;
    h ^= h >> 12;
    return odds != 0 && h % odds == 0;
}

template <class Real, int N>
void check_tree_lanes() {
    using Tree = prism::WideBvhTree<Real, N>;
    std::mt19937 random(7);
    std::uniform_real_distribution<double> uniform(-1, 1), fraction(0, 1);
    // Small boxes in a cube, some flat (a triangle's box in an axis plane).
    std::vector<prism::Aabb<Real>> boxes;
    for (int i = 0; i < 3000; ++i) {
        const glm::dvec3 c(4 * uniform(random), 4 * uniform(random), 4 * uniform(random));
        glm::dvec3 half(0.05 + 0.2 * fraction(random), 0.05 + 0.2 * fraction(random), 0.05 + 0.2 * fraction(random));
        if (i % 5 == 0) half[i % 3] = 0;
        prism::Aabb<Real> box;
        box.extend(prism::Vec3<Real>(c - half));
        box.extend(prism::Vec3<Real>(c + half));
        boxes.push_back(box);
    }
    const Tree tree = Tree::build(std::span<const prism::Aabb<Real>>(boxes));
    const auto& order = tree.primitive_indices();
    std::size_t rays = 0, blocked_rays = 0, leaves = 0;
    for (int batch = 0; batch < 600; ++batch) {
        const int count = 1 + int(fraction(random) * 32);
        const std::uint32_t odds = batch % 4 == 0 ? 0 : 1 + std::uint32_t(batch % 40);  // 0: nothing blocks
        // A row of origins aimed at one point (a row's shadow rays to a light), or anything.
        const glm::dvec3 light(5 * uniform(random), 6, 5 * uniform(random));
        std::vector<prism::Ray<Real>> lane_rays;
        std::vector<typename Tree::TraversalRay> slabs;
        std::array<Real, 32> t_min{}, t_max{};
        for (int i = 0; i < count; ++i) {
            glm::dvec3 origin, direction;
            double length;
            if (batch % 3 != 2) {
                origin = glm::dvec3(-4 + 8.0 * i / count, 4 * uniform(random), -3 + 0.1 * uniform(random));
                direction = glm::normalize(light - origin);
                length = glm::length(light - origin);
            } else {
                origin = 5.0 * glm::dvec3(uniform(random), uniform(random), uniform(random));
                direction = random_unit(random);
                length = 20 * fraction(random);
            }
            if (batch % 7 == 0) direction[i % 3] = 0;  // in a slab's plane: the 0 * inf cases
            if (glm::length(direction) == 0) direction = {0, 1, 0};
            prism::Ray<Real> ray{prism::Vec3<Real>(origin), prism::Vec3<Real>(direction), Real(batch % 5 == 0 ? 1e-3 : 0),
                                 Real(length)};
            lane_rays.push_back(ray);
            slabs.emplace_back(ray);
            t_min[std::size_t(i)] = ray.t_min;
            t_max[std::size_t(i)] = ray.t_max;
        }
        // Every lane, or a random subset of them.
        std::uint32_t lanes = count == 32 ? ~std::uint32_t(0) : (std::uint32_t(1) << count) - 1;
        if (batch % 6 == 1) lanes &= std::uint32_t(random());
        const std::size_t lanes_count = static_cast<std::size_t>(count);
        std::vector<std::set<std::uint32_t>> visited(lanes_count), visited_alone(lanes_count);
        const std::uint32_t blocked = tree.traverse_any_lanes(
            slabs.data(), t_min.data(), t_max.data(), lanes, [&](std::uint32_t first, std::uint32_t n, std::uint32_t testing) {
                CHECK((testing & ~lanes) == 0);
                std::uint32_t hit = 0;
                for (std::uint32_t rest = testing; rest != 0; rest &= rest - 1) {
                    const int i = std::countr_zero(rest);
                    CHECK(visited[std::size_t(i)].insert(first).second);  // no leaf twice
                    for (std::uint32_t k = first; k < first + n; ++k)
                        if (blocks(std::uint32_t(batch * 32 + i), order[k], odds)) {
                            hit |= std::uint32_t(1) << i;
                            break;
                        }
                }
                return hit;
            });
        CHECK((blocked & ~lanes) == 0);
        for (int i = 0; i < count; ++i) {
            if (!((lanes >> i) & 1)) {
                CHECK(visited[std::size_t(i)].empty());
                continue;
            }
            ++rays;
            const bool alone = tree.traverse_any(slabs[std::size_t(i)], t_min[std::size_t(i)], t_max[std::size_t(i)],
                                                 [&](std::uint32_t first, std::uint32_t n, Real&) {
                                                     visited_alone[std::size_t(i)].insert(first);
                                                     for (std::uint32_t k = first; k < first + n; ++k)
                                                         if (blocks(std::uint32_t(batch * 32 + i), order[k], odds)) return true;
                                                     return false;
                                                 });
            CHECK(alone == bool((blocked >> i) & 1));
            blocked_rays += alone;
            // Where nothing blocks, both visit every leaf the ray reaches: the same leaves.
            if (odds == 0) {
                CHECK(visited[std::size_t(i)] == visited_alone[std::size_t(i)]);
                leaves += visited_alone[std::size_t(i)].size();
            }
        }
    }
    CHECK(rays > 5000);
    CHECK(blocked_rays > rays / 10);
    CHECK(blocked_rays < rays * 9 / 10);
    CHECK(leaves > rays);  // the unblocked rays reach many leaves each
}

}  // namespace

TEST_CASE("WideBvhTree::transpose_bits: bit c of byte i becomes bit i of byte c") {
    using Tree = prism::WideBvhTree<float, 8>;
    static_assert(Tree::transpose_bits(0x01) == 0x01);
    static_assert(Tree::transpose_bits(0xff) == 0x0101010101010101ull);  // row 0 full: column 0 of every row
    std::mt19937_64 random(3);
    int wrong = 0;
    for (int k = 0; k < 2000; ++k) {
        const std::uint64_t x = random();
        const std::uint64_t y = Tree::transpose_bits(x);
        for (int i = 0; i < 8; ++i)
            for (int c = 0; c < 8; ++c) wrong += ((x >> (8 * i + c)) & 1) != ((y >> (8 * c + i)) & 1);
        wrong += Tree::transpose_bits(y) != x;
    }
    CHECK(wrong == 0);
}

TEST_CASE_TEMPLATE("WideBvhTree::traverse_any_lanes: each ray reaches the leaves and gets the answer it gets alone", Real,
                   float, double) {
    check_tree_lanes<Real, 8>();
    check_tree_lanes<Real, 4>();
}

// A row's shadow rays (toward one light, from points on the surfaces) and rays of any kind,
// 1 to 32 side by side, in a scene with a top-level index: each answer is occluded's.
TEST_CASE_TEMPLATE("SceneGeometry: shadow rays side by side through the index get what each gets alone", Real, float,
                   double) {
    for (const bool moving : {false, true}) {
        CAPTURE(moving);
        const scene::Scene world = index_scene(moving);
        const auto check = [&](const auto& geometry) {
            REQUIRE(geometry.route() == prism::BatchRoute::index_lanes);
            std::mt19937 random(moving ? 5 : 4);
            std::uniform_real_distribution<double> uniform(-1, 1), fraction(0, 1);
            std::size_t rays = 0, blocked_rays = 0;
            for (int batch = 0; batch < 1500; ++batch) {
                const int count = 1 + int(fraction(random) * 32);
                const glm::dvec3 light(3 * uniform(random), 5, 4 + uniform(random));
                const glm::dvec3 camera(2 * uniform(random), 1.5, 8);
                const Real time = Real(fraction(random));
                std::vector<prism::Ray<Real>> shadows;
                for (int i = 0; i < count; ++i) {
                    // The point a row's camera ray finds, or a point in open space.
                    glm::dvec3 from = 4.0 * glm::dvec3(uniform(random), uniform(random), uniform(random));
                    if (batch % 4 != 3) {
                        prism::Ray<Real> camera_ray{prism::Vec3<Real>(camera),
                                                    prism::Vec3<Real>(glm::normalize(glm::dvec3(-0.5 + double(i) / count, -0.3 + 0.1 * uniform(random), -1))),
                                                    Real(0), prism::infinity<Real>, time};
                        prism::Hit<Real> hit;
                        if (prism::closest_hit(geometry, camera_ray, hit))
                            from = glm::dvec3(camera_ray.origin + camera_ray.direction * hit.t) + 1e-3 * random_unit(random);
                    }
                    glm::dvec3 direction = glm::normalize(light - from);
                    double length = glm::length(light - from);
                    if (batch % 5 == 4) {
                        direction = random_unit(random);
                        length = batch % 2 ? 30.0 : double(prism::infinity<Real>);
                    }
                    shadows.push_back({prism::Vec3<Real>(from), prism::Vec3<Real>(direction), Real(batch % 3 == 0 ? 1e-3 : 0),
                                       Real(length), time});
                }
                std::uint32_t expected = 0;
                for (int i = 0; i < count; ++i)
                    if (prism::blocked(geometry, shadows[std::size_t(i)])) expected |= std::uint32_t(1) << i;
                CHECK(geometry.occluded(prism::RayBatch<Real>::all(shadows.data(), count)) == expected);
                rays += std::size_t(count);
                blocked_rays += std::size_t(std::popcount(expected));
            }
            CHECK(blocked_rays > rays / 10);
            CHECK(blocked_rays < rays * 9 / 10);
        };
        if (moving)
            check(prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>, true>(world));
        else
            check(prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>>(world));
    }
}

// The floor of two triangles (a world-space index of one leaf) tested leaf by leaf in a scene
// that keeps its top-level index: every hit is the exhaustive test's (brute force), to the bit,
// for camera rays under each culling rule and for rays from anywhere.
TEST_CASE_TEMPLATE("SceneGeometry: an index scene's one-leaf world mesh gives the exhaustive test's hits", Real, float,
                   double) {
    using prism::BackfaceCulling;
    const scene::Scene world = index_scene(false);
    const prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>> indexed(world);
    const prism::SceneGeometry<Real, prism::BruteForce<prism::Watertight>> brute(world);
    REQUIRE(indexed.route() == prism::BatchRoute::index_lanes);
    std::mt19937 random(9);
    std::uniform_real_distribution<double> uniform(-1, 1);
    std::size_t floor_hits = 0, differ = 0;
    const std::uint32_t floor_object = 1;
    for (int i = 0; i < 20000; ++i) {
        const glm::dvec3 origin = i % 2 ? glm::dvec3(3 * uniform(random), 2 + uniform(random), 7)
                                        : 5.0 * glm::dvec3(uniform(random), uniform(random), uniform(random));
        const glm::dvec3 target(5.5 * uniform(random), -1, 5.5 * uniform(random));
        const glm::dvec3 direction = i % 3 ? glm::normalize(target - origin) : random_unit(random);
        const prism::Ray<Real> start{prism::Vec3<Real>(origin), prism::Vec3<Real>(direction)};
        for (const BackfaceCulling culling : {BackfaceCulling::none, BackfaceCulling::all}) {
            prism::Ray<Real> a = start, b = start;
            prism::Hit<Real> hit_a, hit_b;
            const bool found_a = culling == BackfaceCulling::none ? prism::closest_hit(indexed, a, hit_a, prism::BackfaceCulling::none)
                                                                  : prism::closest_hit(indexed, a, hit_a, prism::BackfaceCulling::all);
            const bool found_b = culling == BackfaceCulling::none ? prism::closest_hit(brute, b, hit_b, prism::BackfaceCulling::none)
                                                                  : prism::closest_hit(brute, b, hit_b, prism::BackfaceCulling::all);
            if (found_a != found_b || (found_a && (hit_a.object != hit_b.object || !same_bits(hit_a.t, hit_b.t)))) {
                // Only the floor is compared exactly; elsewhere the two may differ on ties.
                if ((found_a && hit_a.object == floor_object) || (found_b && hit_b.object == floor_object)) ++differ;
                continue;
            }
            if (!found_a || hit_a.object != floor_object) continue;
            ++floor_hits;
            // The same triangle at the same point: a mesh alone in its group keeps its index's
            // numbering, brute force the file's, so the surfaces are compared.
            const prism::SurfacePoint<Real> point_a = indexed.surface(a, hit_a), point_b = brute.surface(b, hit_b);
            if (point_a.position != point_b.position || point_a.geometric_normal != point_b.geometric_normal ||
                point_a.shading_normal != point_b.shading_normal)
                ++differ;
        }
    }
    CHECK(differ == 0);
    CHECK(floor_hits > 5000);
}

// Camera rays side by side through the index (one batch through SceneGeometry::intersect in a scene with a
// top-level index: intersect_through_index, WideBvhTree::traverse_closest_lanes): 1 to 32 rays,
// a pixel's samples (nearly one direction), a row's, rays from anywhere, and rays aimed exactly
// at the grids' vertices and edge midpoints, where neighbouring triangles tie and the leaves'
// order decides (the tied rays are traced again alone). Every ray's hit, t_max and answer must
// be intersect's, bit for bit, under each culling rule, still and moving, Watertight and (in
// float) DoubleRefine.
TEST_CASE_TEMPLATE("SceneGeometry: camera rays side by side through the index get intersect's hits", Real, float,
                   double) {
    using prism::BackfaceCulling;
    for (const bool moving : {false, true}) {
        CAPTURE(moving);
        const scene::Scene world = index_scene(moving);
        // The grids' vertices and edge midpoints in world space: targets where triangles meet.
        std::vector<glm::dvec3> corners;
        for (std::size_t m : {std::size_t(0), std::size_t(2)}) {
            const scene::Mesh& mesh = world.meshes[m];
            for (const auto& face : mesh.triangles)
                for (int k = 0; k < 3; ++k) {
                    const glm::dvec3 a = mesh.positions[face[std::size_t(k)]], b = mesh.positions[face[std::size_t((k + 1) % 3)]];
                    for (const glm::dvec3& p : {a, 0.5 * (a + b)})
                        corners.push_back(glm::dvec3(mesh.transform * glm::dvec4(p, 1.0)));
                }
        }
        const auto check = [&](const auto& geometry) {
            REQUIRE(geometry.route() == prism::BatchRoute::index_lanes);
            std::mt19937 random(moving ? 15 : 14);
            std::uniform_real_distribution<double> uniform(-1, 1), fraction(0, 1);
            std::size_t rays = 0, hit_rays = 0, edge_hits = 0, differ = 0;
            for (int batch = 0; batch < 1200; ++batch) {
                const int count = 1 + int(fraction(random) * 32);
                const glm::dvec3 camera(2 * uniform(random), 1.5 + uniform(random), 8);
                const glm::dvec3 aim = glm::normalize(glm::dvec3(0.4 * uniform(random), -0.3 + 0.2 * uniform(random), -1));
                const Real time = Real(fraction(random));
                std::vector<prism::Ray<Real>> start;
                for (int i = 0; i < count; ++i) {
                    glm::dvec3 origin = camera, direction;
                    switch (batch % 4) {
                        case 0: direction = glm::normalize(aim + 1e-3 * glm::dvec3(uniform(random), uniform(random), 0)); break;
                        case 1: direction = glm::normalize(aim + glm::dvec3(-0.3 + 0.6 * i / count, 0.02 * uniform(random), 0)); break;
                        case 2:
                            origin = 5.0 * glm::dvec3(uniform(random), uniform(random), uniform(random));
                            direction = random_unit(random);
                            break;
                        default:
                            direction = glm::normalize(corners[std::size_t(random()) % corners.size()] - origin);
                            break;
                    }
                    start.push_back({prism::Vec3<Real>(origin), prism::Vec3<Real>(direction), Real(batch % 5 == 0 ? 1e-3 : 0),
                                     batch % 7 == 0 ? Real(6) : prism::infinity<Real>, time});
                }
                const auto compare = [&]<BackfaceCulling Culling>() {
                    std::vector<prism::Ray<Real>> alone = start, together = start;
                    std::vector<prism::Hit<Real>> hits_alone(static_cast<std::size_t>(count)), hits_together(static_cast<std::size_t>(count));
                    std::uint32_t expected = 0;
                    for (int i = 0; i < count; ++i)
                        if (prism::closest_hit(geometry, alone[std::size_t(i)], hits_alone[std::size_t(i)], Culling))
                            expected |= std::uint32_t(1) << i;
                    const std::uint32_t found = geometry.intersect(prism::RayBatch<Real>::all(together.data(), count, Culling), hits_together.data());
                    differ += found != expected;
                    for (int i = 0; i < count; ++i) {
                        const auto& a = hits_alone[std::size_t(i)];
                        const auto& b = hits_together[std::size_t(i)];
                        differ += !same_bits(alone[std::size_t(i)].t_max, together[std::size_t(i)].t_max);
                        if (!((expected >> i) & 1)) continue;
                        differ += !same_bits(a.t, b.t) || a.object != b.object || a.primitive != b.primitive ||
                                  !same_bits(a.b1, b.b1) || !same_bits(a.b2, b.b2);
                        ++hit_rays;
                        edge_hits += a.b1 == 0 || a.b2 == 0 || a.b1 + a.b2 == 1;
                    }
                    rays += std::size_t(count);
                    // With a random active mask, gaps included: the active rays as alone, the
                    // others untouched.
                    std::vector<prism::Ray<Real>> masked = start;
                    const std::uint32_t mask = std::uint32_t(random()) & prism::RayBatch<Real>::all(masked.data(), count).active;
                    std::vector<prism::Hit<Real>> masked_hits(static_cast<std::size_t>(count));
                    for (auto& hit : masked_hits) hit.object = 12345;
                    const std::uint32_t masked_found =
                        geometry.intersect(prism::RayBatch<Real>{masked.data(), count, mask, Culling}, masked_hits.data());
                    differ += masked_found != (expected & mask);
                    for (int i = 0; i < count; ++i) {
                        const std::size_t k = std::size_t(i);
                        if (!((mask >> i) & 1)) {
                            differ += !same_bits(masked[k].t_max, start[k].t_max) || masked_hits[k].object != 12345;
                            continue;
                        }
                        differ += !same_bits(masked[k].t_max, alone[k].t_max);
                        if ((expected >> i) & 1)
                            differ += !same_bits(masked_hits[k].t, hits_alone[k].t) ||
                                      masked_hits[k].object != hits_alone[k].object ||
                                      masked_hits[k].primitive != hits_alone[k].primitive;
                    }
                };
                compare.template operator()<BackfaceCulling::none>();
                compare.template operator()<BackfaceCulling::triangles>();
                compare.template operator()<BackfaceCulling::all>();
            }
            CHECK(differ == 0);
            CHECK(hit_rays > rays / 2);
            CHECK(edge_hits > 100);  // rays through shared edges and vertices, where the order decides a tie
        };
        if (moving) {
            check(prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>, true>(world));
            check(prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 4>, true>(world));
        } else {
            check(prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>>(world));
        }
        if constexpr (std::is_same_v<Real, float>) check(prism::SceneGeometry<Real, prism::WideBvh<prism::DoubleRefine, 8>, true>(world));
    }
}
