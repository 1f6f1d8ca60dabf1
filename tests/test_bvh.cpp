// The BVH against brute force, for float and double: the closest hit (hit or miss, t, object,
// triangle) and the any-hit query on 10^5 random rays over a course mesh with a sphere, and on
// 10^4 rays over a procedural mesh with a transformed instance of it and a sphere, so the top
// level is exercised too; then the tree's structure (every primitive in exactly one leaf,
// children inside their parent, bounded depth), the degenerate inputs (no triangles, one
// triangle, many triangles with one centroid, a geometric progression that drives the build to
// its depth limit) and SceneGeometry's hit interval and back-face culling.
#include <prism/accel/accelerator.hpp>
#include <prism/geometry/scene_geometry.hpp>
#include <prism/io/ply.hpp>
#include <prism/memory/huge_page_allocator.hpp>

#include <glm/gtc/matrix_transform.hpp>

#include <doctest/doctest.h>
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <typeinfo>
#include <utility>
#include <vector>

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif

namespace {

namespace scene = prism::scene;

template <class Real>
using BvhGeometry = prism::SceneGeometry<Real, prism::Bvh<prism::Watertight>>;
template <class Real>
using BruteGeometry = prism::SceneGeometry<Real, prism::BruteForce<prism::Watertight>>;

// Runs `body.template operator()<Geometry>()` for the binary BVH and the wide BVHs (4 and 8).
template <class Real, class Body>
void for_each_bvh(Body body) {
    body.template operator()<BvhGeometry<Real>>();
    body.template operator()<prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 4>>>();
    body.template operator()<prism::SceneGeometry<Real, prism::WideBvh<prism::Watertight, 8>>>();
}

// ---------------------------------------------------------------------------------------------
// Scenes

// The mesh is stored as a vertex soup in which every vertex of triangle i carries the texture
// coordinate (i, 0): the interpolated u of a hit is then i, which names the triangle hit in the
// scene's own numbering whatever order an index keeps its triangles in. The geometry is the
// same as the shared-vertex mesh, vertex for vertex.
scene::Mesh soup_with_triangle_ids(const std::vector<glm::dvec3>& positions,
                                   const std::vector<std::array<std::uint32_t, 3>>& triangles) {
    scene::Mesh mesh;
    mesh.id = "under test";
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        const auto first = std::uint32_t(mesh.positions.size());
        for (std::uint32_t v : triangles[i]) {
            mesh.positions.push_back(positions[v]);
            mesh.uvs.push_back({double(i), 0.0});
        }
        mesh.triangles.push_back({first, first + 1, first + 2});
    }
    return mesh;
}

struct Bounds {
    glm::dvec3 min{std::numeric_limits<double>::infinity()}, max{-std::numeric_limits<double>::infinity()};
    glm::dvec3 centre() const { return (min + max) * 0.5; }
    double radius() const { return glm::length(max - min) * 0.5; }
};

Bounds bounds_of(const std::vector<glm::dvec3>& positions) {
    Bounds b;
    for (const auto& p : positions) {
        b.min = glm::min(b.min, p);
        b.max = glm::max(b.max, p);
    }
    return b;
}

// Object 0: the mesh; with `with_instance`, object 1: the same mesh rotated, scaled and moved
// by a third of its size (an instance sharing the mesh's index); last: a sphere in a corner of
// the bounds, where the mesh does not hide it.
scene::Scene mesh_scene(const scene::Mesh& mesh, const Bounds& bounds, bool with_instance) {
    scene::Scene world;
    world.materials.push_back({});
    world.meshes.push_back(mesh);
    const double r = bounds.radius();
    world.spheres.push_back({"ball", 0, bounds.min + 0.1 * (bounds.max - bounds.min), 0.15 * r, glm::dmat4(1.0)});
    if (!with_instance) return world;
    glm::dmat4 transform(1.0);
    transform = glm::translate(transform, bounds.centre() + glm::dvec3(0.3 * r, -0.2 * r, 0.25 * r));
    transform = glm::rotate(transform, 0.7, glm::normalize(glm::dvec3(1, 2, 3)));
    transform = glm::scale(transform, glm::dvec3(0.8, 1.1, 0.9));
    transform = glm::translate(transform, -bounds.centre());
    world.mesh_instances.push_back({"moved copy", 0, 0, transform});
    return world;
}

// A unit icosphere subdivided `levels` times, every vertex moved radially by up to +-15%.
void perturbed_sphere(int levels, std::uint32_t seed, std::vector<glm::dvec3>& positions,
                      std::vector<std::array<std::uint32_t, 3>>& triangles) {
    const double g = (1.0 + std::sqrt(5.0)) / 2.0;
    positions = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                 {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    for (auto& p : positions) p = glm::normalize(p);
    triangles = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    for (int level = 0; level < levels; ++level) {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoints;
        auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
            const auto key = std::minmax(a, b);
            const auto found = midpoints.find(key);
            if (found != midpoints.end()) return found->second;
            positions.push_back(glm::normalize(positions[a] + positions[b]));
            const auto index = std::uint32_t(positions.size() - 1);
            midpoints.emplace(key, index);
            return index;
        };
        std::vector<std::array<std::uint32_t, 3>> finer;
        for (const auto& t : triangles) {
            const std::uint32_t ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
            finer.push_back({t[0], ab, ca});
            finer.push_back({t[1], bc, ab});
            finer.push_back({t[2], ca, bc});
            finer.push_back({ab, bc, ca});
        }
        triangles = std::move(finer);
    }
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> bump(0.85, 1.15);
    for (auto& p : positions) p *= bump(random);
}

// ---------------------------------------------------------------------------------------------
// Rays

std::vector<glm::dvec3> random_unit_vectors(std::mt19937& random, std::size_t count) {
    std::normal_distribution<double> normal;
    std::vector<glm::dvec3> result;
    while (result.size() < count) {
        const glm::dvec3 v(normal(random), normal(random), normal(random));
        if (glm::length(v) > 1e-6) result.push_back(glm::normalize(v));
    }
    return result;
}

// Origins on a sphere around the bounds. 70% aim at random points inside the bounds (most hit),
// 10% aim exactly at mesh vertices (where triangles share edges and the slab tests of flat
// boxes are tight), 20% go in random directions.
template <class Real>
std::vector<prism::Ray<Real>> test_rays(const Bounds& bounds, const std::vector<glm::dvec3>& vertices,
                                        std::size_t count, std::uint32_t seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    const auto on_sphere = random_unit_vectors(random, count);
    const auto directions = random_unit_vectors(random, count);
    std::uniform_int_distribution<std::size_t> vertex(0, vertices.size() - 1);
    std::vector<prism::Ray<Real>> rays;
    rays.reserve(count);
    for (std::size_t i = 0; i < count; ++i) {
        const glm::dvec3 origin = bounds.centre() + 1.5 * bounds.radius() * on_sphere[i];
        glm::dvec3 direction;
        const double kind = uniform(random);
        if (kind < 0.7) {
            const glm::dvec3 target = bounds.min + glm::dvec3(uniform(random), uniform(random), uniform(random)) *
                                                       (bounds.max - bounds.min);
            direction = glm::normalize(target - origin);
        } else if (kind < 0.8) {
            direction = glm::normalize(vertices[vertex(random)] - origin);
        } else {
            direction = directions[i];
        }
        rays.push_back({prism::Vec3<Real>(origin), prism::Vec3<Real>(direction), Real(0), prism::infinity<Real>});
    }
    return rays;
}

// ---------------------------------------------------------------------------------------------
// Tracing and comparing

template <class Real>
struct Trace {
    bool hit = false;
    Real t = prism::infinity<Real>;
    std::uint32_t object = 0;
    long triangle = -1;  // from the texture coordinate; -1 for the sphere (the last object)
    prism::Vec3<Real> normal{0};
    bool t_max_lowered = true;  // intersect must leave ray.t_max at the hit distance
    bool occluded_unbounded = false;
    bool occluded_half = false;  // with t_max = half the brute-force distance
};

// Brute force costs a full scan per query, so its any-hit answers are computed on every
// `any_hit_stride`-th ray only; the BVH's any-hit answers are checked on every ray against the
// brute-force closest hit, which decides them.
constexpr std::size_t any_hit_stride = 10;

template <class Real, class Geometry>
void trace_all(const Geometry& geometry, const std::vector<prism::Ray<Real>>& rays, std::size_t stride,
               std::vector<Trace<Real>>& traces) {
    const auto sphere = std::uint32_t(geometry.instance_count() - 1);
    traces.resize(rays.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 64), [&](const auto& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            Trace<Real>& trace = traces[i];
            prism::Ray<Real> ray = rays[i];
            prism::Hit<Real> hit;
            trace.hit = prism::closest_hit(geometry, ray, hit);
            if (trace.hit) {
                trace.t = hit.t;
                trace.t_max_lowered = ray.t_max == hit.t;
                trace.object = hit.object;
                const prism::SurfacePoint<Real> point = geometry.surface(ray, hit);
                trace.normal = point.geometric_normal;
                trace.triangle = hit.object == sphere ? -1 : std::lround(double(point.uv.x));
            }
            if (i % stride == 0) trace.occluded_unbounded = prism::blocked(geometry, rays[i]);
        }
    });
}

// The any-hit query with t_max at half the reference distance: nothing can lie that close.
template <class Real, class Geometry>
void occluded_at_half(const Geometry& geometry, const std::vector<prism::Ray<Real>>& rays,
                      const std::vector<Trace<Real>>& reference, std::size_t stride,
                      std::vector<Trace<Real>>& traces) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 64), [&](const auto& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            if (!reference[i].hit || i % stride != 0) continue;
            prism::Ray<Real> ray = rays[i];
            ray.t_max = reference[i].t / 2;
            traces[i].occluded_half = prism::blocked(geometry, ray);
        }
    });
}

// The t that the watertight test gives for one triangle of the mesh or its instance (or the
// sphere), with the ray taken to object space exactly as SceneGeometry does. Used to confirm
// that two different answers are a genuine tie.
template <class Real, class Intersector = prism::Watertight>
bool direct_hit(const scene::Scene& world, const prism::Ray<Real>& world_ray, std::uint32_t object, long triangle,
                Real& t) {
    prism::Ray<Real> ray = world_ray;
    const bool instance = !world.mesh_instances.empty() && object == 1;
    if (instance) {
        const glm::dmat4 inverse = glm::inverse(world.mesh_instances[0].transform);
        const prism::Mat4<Real> to_object(inverse);
        const prism::Mat3<Real> to_object_linear{glm::dmat3(inverse)};
        ray = {prism::Vec3<Real>(to_object * prism::Vec4<Real>(ray.origin, 1)), to_object_linear * ray.direction,
               ray.t_min, ray.t_max};
    }
    if (triangle < 0) {
        const prism::SphereShape<Real> sphere{prism::Vec3<Real>(world.spheres[0].center), Real(world.spheres[0].radius)};
        return sphere.intersect(ray, ray.t_min, prism::infinity<Real>, t);
    }
    const scene::Mesh& mesh = world.meshes[0];
    const auto& face = mesh.triangles[std::size_t(triangle)];
    prism::TriangleHit<Real> hit;
    using Storage = typename Intersector::template Storage<Real>;
    const typename Intersector::template Prepared<Real> prepared(ray);
    if (!Intersector::intersect(prepared, prism::Vec3<Storage>(mesh.positions[face[0]]),
                                prism::Vec3<Storage>(mesh.positions[face[1]]),
                                prism::Vec3<Storage>(mesh.positions[face[2]]), ray.t_min, prism::infinity<Real>, hit))
        return false;
    t = hit.t;
    return true;
}

template <class Real>
std::string describe(const prism::Ray<Real>& ray, const Trace<Real>& bvh, const Trace<Real>& brute) {
    std::ostringstream out;
    out.precision(17);
    out << "ray o=(" << ray.origin.x << ", " << ray.origin.y << ", " << ray.origin.z << ") d=(" << ray.direction.x << ", "
        << ray.direction.y << ", " << ray.direction.z << "): bvh hit=" << bvh.hit << " t=" << bvh.t << " object="
        << bvh.object << " triangle=" << bvh.triangle << " | brute hit=" << brute.hit << " t=" << brute.t
        << " object=" << brute.object << " triangle=" << brute.triangle;
    return out.str();
}

// Runs each policy's geometry and brute force (with the same intersector) on the rays and counts
// every kind of disagreement; the first few are printed so a failure can be reproduced.
template <class Real, class Intersector, class Policy>
void compare_policy_with_brute_force(const scene::Scene& world, const std::vector<prism::Ray<Real>>& rays,
                                     const std::vector<Trace<Real>>& brute_traces);

template <class Real, class Intersector, class... Policies>
void compare_with_brute_force(const scene::Scene& world, const std::vector<prism::Ray<Real>>& rays) {
    const prism::SceneGeometry<Real, prism::BruteForce<Intersector>> brute(world);
    std::vector<Trace<Real>> brute_traces;
    trace_all(brute, rays, any_hit_stride, brute_traces);
    occluded_at_half(brute, rays, brute_traces, any_hit_stride, brute_traces);
    (compare_policy_with_brute_force<Real, Intersector, Policies>(world, rays, brute_traces), ...);
}

template <class Real, class Intersector, class Policy>
void compare_policy_with_brute_force(const scene::Scene& world, const std::vector<prism::Ray<Real>>& rays,
                                     const std::vector<Trace<Real>>& brute_traces) {
    static_assert(std::is_same_v<typename Policy::Intersector, Intersector>);
    const prism::SceneGeometry<Real, Policy> bvh(world);
    const std::size_t copies = 1 + world.mesh_instances.size();
    REQUIRE(bvh.instance_count() == copies + 1);
    REQUIRE(bvh.triangle_count() == copies * world.meshes[0].triangles.size());
    const std::size_t sphere = copies;

    std::vector<Trace<Real>> bvh_traces;
    trace_all(bvh, rays, 1, bvh_traces);
    occluded_at_half(bvh, rays, brute_traces, 1, bvh_traces);

    std::size_t hits = 0, ties = 0, per_object[3] = {0, 0, 0};  // mesh, instance, sphere
    std::size_t hit_mismatch = 0, t_mismatch = 0, identity_mismatch = 0, near_ties = 0, t_max_not_lowered = 0;
    std::size_t occluded_mismatch = 0, brute_occluded_mismatch = 0;
    int printed = 0;
    auto report = [&](std::size_t i, const char* what) {
        if (printed++ >= 4) return;
        const std::string message = std::string(what) + ": " + describe(rays[i], bvh_traces[i], brute_traces[i]);
        MESSAGE(message);
    };
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const Trace<Real>& a = bvh_traces[i];
        const Trace<Real>& b = brute_traces[i];
        if (!a.t_max_lowered || !b.t_max_lowered) ++t_max_not_lowered;
        // Any hit: unbounded it is the closest hit's hit/miss; below half the closest distance
        // there is nothing.
        if (a.occluded_unbounded != b.hit || a.occluded_half) {
            ++occluded_mismatch;
            report(i, "bvh occluded");
        }
        if (i % any_hit_stride == 0 && (b.occluded_unbounded != b.hit || b.occluded_half)) {
            ++brute_occluded_mismatch;
            report(i, "brute-force occluded");
        }
        if (a.hit != b.hit) {
            ++hit_mismatch;
            report(i, "hit/miss");
            continue;
        }
        if (!a.hit) continue;
        ++hits;
        ++per_object[b.object == sphere ? 2 : b.object];
        const bool same_primitive = a.object == b.object && a.triangle == b.triangle;
        if (same_primitive) {
            // The same test on the same triangle and ray: t and normal must agree to the bit.
            if (a.t != b.t || a.normal != b.normal) {
                ++t_mismatch;
                report(i, "same primitive, different t or normal");
            }
            continue;
        }
        // Different primitives: acceptable only as a tie, both genuinely hit at the same t.
        Real t_a = -1, t_b = -1;
        const bool real_a = direct_hit<Real, Intersector>(world, rays[i], a.object, a.triangle, t_a);
        const bool real_b = direct_hit<Real, Intersector>(world, rays[i], b.object, b.triangle, t_b);
        if (real_a && real_b && t_a == a.t && t_b == b.t && a.t == b.t) {
            ++ties;
        } else if (a.t == b.t) {
            ++identity_mismatch;
            report(i, "different primitive, not a genuine tie");
        } else {
            ++near_ties;
            report(i, "different primitive at a different t");
        }
    }
    MESSAGE(std::string(typeid(Policy).name()) << ": " << rays.size() << " rays: " << hits << " hits (mesh " << per_object[0] << ", instance " << per_object[1]
                        << ", sphere " << per_object[2] << "), " << ties << " exact ties between triangles");
    // The ray set must exercise what it claims to: most rays hit, some miss, every object is hit.
    CHECK(hits > rays.size() / 2);
    CHECK(hits < rays.size());
    CHECK(per_object[0] > rays.size() / 20);
    if (copies == 2) CHECK(per_object[1] > rays.size() / 20);
    CHECK(per_object[2] > rays.size() / 100);

    CHECK(hit_mismatch == 0);
    CHECK(t_mismatch == 0);
    CHECK(identity_mismatch == 0);
    CHECK(near_ties == 0);
    CHECK(t_max_not_lowered == 0);
    CHECK(occluded_mismatch == 0);
    CHECK(brute_occluded_mismatch == 0);
}


}  // namespace

// 10^5 rays against 2,880 triangles and a sphere, brute force included, stay within a few
// seconds on two cores; a larger course mesh would make the brute-force reference the bottleneck.
TEST_CASE_TEMPLATE("BVH closest hit and any hit equal brute force on a course mesh", Real, float, double) {
    const std::filesystem::path path = std::filesystem::path(PRISM_SHARED_DIR) /
                                       "ceng795/hw4/2022F_Batucan2601/hw4/inputs/veach_ajar/models/Mesh015_fixed.ply";
    if (!std::filesystem::exists(path)) {
        MESSAGE("skipped: " << path.string() << " not found (set PRISM_SHARED_DIR)");
        return;
    }
    const prism::io::PlyMesh ply = prism::io::read_ply(path);
    REQUIRE(ply.triangles.size() == 2880);
    const Bounds bounds = bounds_of(ply.positions);
    const scene::Scene world = mesh_scene(soup_with_triangle_ids(ply.positions, ply.triangles), bounds, false);
    compare_with_brute_force<Real, prism::Watertight, prism::Bvh<prism::Watertight>, prism::WideBvh<prism::Watertight, 4>,
                             prism::WideBvh<prism::Watertight, 8>>(world,
                                                                   test_rays<Real>(bounds, ply.positions, 100'000, 2013));
}

TEST_CASE_TEMPLATE("BVH closest hit and any hit equal brute force on a perturbed icosphere", Real, float, double) {
    std::vector<glm::dvec3> positions;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    perturbed_sphere(4, 7, positions, triangles);
    REQUIRE(triangles.size() == 5120);
    const Bounds bounds = bounds_of(positions);
    // The instance adds the transformed object space and the top-level index to the comparison.
    const scene::Scene world = mesh_scene(soup_with_triangle_ids(positions, triangles), bounds, true);
    const auto rays = test_rays<Real>(bounds, positions, 10'000, 1980);
    compare_with_brute_force<Real, prism::Watertight, prism::Bvh<prism::Watertight>, prism::WideBvh<prism::Watertight, 4>,
                             prism::WideBvh<prism::Watertight, 8>>(world, rays);
    compare_with_brute_force<Real, prism::DoubleRefine, prism::WideBvh<prism::DoubleRefine, 4>,
                             prism::WideBvh<prism::DoubleRefine, 8>>(world, rays);
}

// ---------------------------------------------------------------------------------------------
// The tree's structure

namespace {

template <class Real>
bool encloses(const prism::Aabb<Real>& outer, const prism::Aabb<Real>& inner) {
    return glm::all(glm::lessThanEqual(outer.min, inner.min)) && glm::all(glm::lessThanEqual(inner.max, outer.max));
}

// Every primitive in exactly one leaf, every node reached exactly once from the root, children
// inside their parent, leaves around their primitives, depth within the traversal stack.
template <class Real>
void check_structure(const prism::BvhTree<Real>& tree, const std::vector<prism::Aabb<Real>>& boxes,
                     std::uint32_t max_leaf_size) {
    const auto& nodes = tree.nodes();
    const auto& order = tree.primitive_indices();
    REQUIRE(order.size() == boxes.size());
    std::vector<int> times_listed(boxes.size(), 0);
    for (std::uint32_t p : order)
        if (p < boxes.size()) ++times_listed[p];
    CHECK(std::count(times_listed.begin(), times_listed.end(), 1) == std::ptrdiff_t(boxes.size()));
    if (boxes.empty()) {
        CHECK(nodes.empty());
        CHECK(tree.depth() == 0);
        return;
    }
    REQUIRE(!nodes.empty());
    CHECK(nodes.size() <= 2 * boxes.size() - 1);

    std::vector<int> slot_in_leaves(boxes.size(), 0), node_visits(nodes.size(), 0);
    std::size_t child_outside = 0, primitive_outside = 0, oversized_leaves = 0, bad_index = 0;
    int deepest = 0;
    std::vector<std::pair<std::uint32_t, int>> stack{{0u, 1}};
    while (!stack.empty()) {
        const auto [index, depth] = stack.back();
        stack.pop_back();
        ++node_visits[index];
        deepest = std::max(deepest, depth);
        const prism::BvhNode<Real>& node = nodes[index];
        if (node.is_leaf()) {
            if (std::size_t(node.index) + node.count > boxes.size()) {
                ++bad_index;
                continue;
            }
            if (node.count > max_leaf_size) ++oversized_leaves;
            for (std::uint32_t slot = node.index; slot < node.index + node.count; ++slot) {
                ++slot_in_leaves[slot];
                if (!encloses(node.bounds, boxes[order[slot]])) ++primitive_outside;
            }
            continue;
        }
        if (node.index == 0 || std::size_t(node.index) + 1 >= nodes.size()) {
            ++bad_index;
            continue;
        }
        for (std::uint32_t child : {node.index, node.index + 1}) {
            if (!encloses(node.bounds, nodes[child].bounds)) ++child_outside;
            stack.push_back({child, depth + 1});
        }
    }
    CHECK(bad_index == 0);
    CHECK(std::count(slot_in_leaves.begin(), slot_in_leaves.end(), 1) == std::ptrdiff_t(boxes.size()));
    CHECK(std::count(node_visits.begin(), node_visits.end(), 1) == std::ptrdiff_t(nodes.size()));
    CHECK(child_outside == 0);
    CHECK(primitive_outside == 0);
    CHECK(oversized_leaves == 0);
    CHECK(deepest == tree.depth());
    CHECK(tree.depth() < prism::BvhTree<Real>::max_depth);
    prism::Aabb<Real> all;
    for (const auto& box : boxes) all.extend(box);
    CHECK(encloses(tree.bounds(), all));
}

// Whether two wide trees are the same, node for node and bit for bit: compared field by field,
// since a node of double lanes has padding.
template <class Tree>
void check_same_wide_trees(const Tree& a, const Tree& b) {
    REQUIRE(a.nodes().size() == b.nodes().size());
    std::size_t different = 0;
    for (std::size_t i = 0; i < a.nodes().size(); ++i) {
        const auto &x = a.nodes()[i], &y = b.nodes()[i];
        different += std::memcmp(x.bounds, y.bounds, sizeof x.bounds) != 0 || std::memcmp(x.child, y.child, sizeof x.child) != 0;
    }
    CHECK(different == 0);
    CHECK(a.primitive_indices() == b.primitive_indices());
    const auto box_a = a.bounds(), box_b = b.bounds();
    CHECK(std::memcmp(&box_a, &box_b, sizeof box_a) == 0);
}

template <class Real>
std::vector<prism::Aabb<Real>> triangle_boxes(const std::vector<glm::dvec3>& positions,
                                              const std::vector<std::array<std::uint32_t, 3>>& triangles) {
    std::vector<prism::Aabb<Real>> boxes(triangles.size());
    for (std::size_t i = 0; i < triangles.size(); ++i)
        for (std::uint32_t v : triangles[i]) boxes[i].extend(prism::Vec3<Real>(positions[v]));
    return boxes;
}

// Rays from all around at the triangle's vertices, at points on its edges and inside it.
template <class Real>
std::vector<prism::Ray<Real>> rays_at_triangle(const std::array<glm::dvec3, 3>& triangle, std::size_t count,
                                               std::mt19937& random) {
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    const auto directions = random_unit_vectors(random, count);
    std::vector<prism::Ray<Real>> rays;
    for (std::size_t i = 0; i < count; ++i) {
        glm::dvec3 target = triangle[i % 3];
        if (i % 4 == 1) target = glm::mix(triangle[i % 3], triangle[(i + 1) % 3], uniform(random));
        if (i % 4 == 2) {
            const double b1 = uniform(random), b2 = uniform(random) * (1 - b1);
            target = (1 - b1 - b2) * triangle[0] + b1 * triangle[1] + b2 * triangle[2];
        }
        const glm::dvec3 origin = target - (0.5 + 3 * uniform(random)) * directions[i];
        rays.push_back({prism::Vec3<Real>(origin), prism::Vec3<Real>(glm::normalize(target - origin)), Real(0),
                        prism::infinity<Real>});
    }
    return rays;
}

}  // namespace

TEST_CASE_TEMPLATE("BVH structure: a mesh, random boxes, one centroid, a geometric progression", Real, float, double) {
    const std::uint32_t max_leaf_size = prism::BvhBuildOptions{}.max_leaf_size;
    SUBCASE("perturbed icosphere, built in parallel") {
        std::vector<glm::dvec3> positions;
        std::vector<std::array<std::uint32_t, 3>> triangles;
        perturbed_sphere(5, 11, positions, triangles);  // 20,480 triangles: above the parallel threshold
        const auto boxes = triangle_boxes<Real>(positions, triangles);
        const auto tree = prism::BvhTree<Real>::build(boxes);
        check_structure(tree, boxes, max_leaf_size);
        CHECK(tree.depth() > 10);  // a real hierarchy, not one leaf
    }
    SUBCASE("random boxes of every size") {
        std::mt19937 random(5);
        std::uniform_real_distribution<double> uniform(-100.0, 100.0), size(0.0, 10.0);
        std::vector<prism::Aabb<Real>> boxes(3000);
        for (auto& box : boxes) {
            const prism::Vec3<Real> corner(Real(uniform(random)), Real(uniform(random)), Real(uniform(random)));
            box.extend(corner);
            box.extend(corner + prism::Vec3<Real>(Real(size(random)), Real(size(random)), Real(size(random))));
        }
        check_structure(prism::BvhTree<Real>::build(boxes), boxes, max_leaf_size);
    }
    SUBCASE("one centroid: copies of one box, and boxes nested around one centre") {
        // SAH finds no plane between equal centroids; the build must still split by count.
        std::vector<prism::Aabb<Real>> boxes(1000, prism::Aabb<Real>{prism::Vec3<Real>(-1), prism::Vec3<Real>(1)});
        for (std::size_t i = 0; i < 500; ++i) {
            const Real half = Real(0.01) * Real(i + 1);
            boxes[2 * i] = {prism::Vec3<Real>(-half), prism::Vec3<Real>(half)};
        }
        const auto tree = prism::BvhTree<Real>::build(boxes);
        check_structure(tree, boxes, max_leaf_size);
        CHECK(tree.depth() <= 10);  // halving 1000 down to leaves of 8: about 8 levels
    }
    SUBCASE("a geometric progression of positions and sizes") {
        // Each split peels off the few largest boxes, so the tree gets deep; the build must
        // stop splitting before the traversal stack (64) overflows.
        std::vector<prism::Aabb<Real>> boxes;
        const int count = std::is_same_v<Real, float> ? 120 : 1000;
        for (int i = 0; i < count; ++i) {
            const Real x = std::ldexp(Real(1), -i);
            boxes.push_back({prism::Vec3<Real>(x, 0, 0), prism::Vec3<Real>(x + x / 2, x / 2, x / 2)});
        }
        const auto tree = prism::BvhTree<Real>::build(boxes);
        check_structure(tree, boxes, std::uint32_t(boxes.size()));  // the depth cap may leave big leaves
        MESSAGE("geometric progression of " << count << " boxes: depth " << tree.depth());
        // Traversal reaches every leaf, the deepest included: a ray down through each box.
        std::size_t unreached = 0;
        const auto& order = tree.primitive_indices();
        for (int i = 0; i < count; ++i) {
            const Real x = std::ldexp(Real(1), -i);
            const prism::Ray<Real> ray{prism::Vec3<Real>(x + x / 4, x / 4, 1), prism::Vec3<Real>(0, 0, -1), Real(0),
                                       prism::infinity<Real>};
            const bool reached = tree.traverse_any(ray, prism::infinity<Real>, [&](std::uint32_t first, std::uint32_t n, Real&) {
                return std::find(order.begin() + first, order.begin() + first + n, std::uint32_t(i)) != order.begin() + first + n;
            });
            unreached += reached ? 0 : 1;
        }
        CHECK(unreached == 0);
    }
}

namespace {

// The subtrees a wide collapse turns into leaves: each highest node over at most max_leaf_size
// primitives, as its box and its primitives (sorted, as a set).
template <class Real>
struct SmallSubtree {
    prism::Aabb<Real> bounds;
    std::vector<std::uint32_t> primitives;
    bool operator<(const SmallSubtree& other) const { return primitives < other.primitives; }
};

template <class Real>
void collect_small_subtrees(const prism::BvhTree<Real>& tree, std::uint32_t index, std::uint32_t max_leaf_size,
                            std::vector<SmallSubtree<Real>>& out, std::vector<std::uint32_t>* gathered = nullptr) {
    const prism::BvhNode<Real>& node = tree.nodes()[index];
    std::vector<std::uint32_t> primitives;
    if (node.is_leaf()) {
        const auto& order = tree.primitive_indices();
        primitives.assign(order.begin() + node.index, order.begin() + node.index + node.count);
    } else {
        std::vector<SmallSubtree<Real>> below;
        collect_small_subtrees(tree, node.index, max_leaf_size, below, &primitives);
        collect_small_subtrees(tree, node.index + 1, max_leaf_size, below, &primitives);
        if (primitives.size() > max_leaf_size) out.insert(out.end(), below.begin(), below.end());
    }
    if (gathered != nullptr) gathered->insert(gathered->end(), primitives.begin(), primitives.end());
    if (primitives.size() <= max_leaf_size) {
        std::sort(primitives.begin(), primitives.end());
        out.push_back({node.bounds, std::move(primitives)});
    }
}

}  // namespace

TEST_CASE_TEMPLATE("BVH stopped at the leaf size: the leaves the full build's collapse would make", Real, float, double) {
    // The wide BVH builds its binary tree with leaf_at_max_size: no node of at most
    // max_leaf_size primitives is split. Its leaves must be exactly the full build's highest
    // subtrees of that size, with the same boxes; only the order inside a leaf may differ.
    std::vector<glm::dvec3> positions;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    perturbed_sphere(5, 11, positions, triangles);  // 20,480 triangles: above the parallel threshold
    const auto boxes = triangle_boxes<Real>(positions, triangles);
    for (const std::uint32_t max_leaf_size : {4u, 8u}) {
        CAPTURE(max_leaf_size);
        const auto full = prism::BvhTree<Real>::build(boxes, {.max_leaf_size = max_leaf_size});
        const auto stopped = prism::BvhTree<Real>::build(boxes, {.max_leaf_size = max_leaf_size, .leaf_at_max_size = true});
        check_structure(stopped, boxes, max_leaf_size);
        CHECK(stopped.nodes().size() < full.nodes().size());
        std::vector<SmallSubtree<Real>> expected, leaves;
        collect_small_subtrees(full, 0, max_leaf_size, expected);
        for (const auto& node : stopped.nodes()) {
            if (!node.is_leaf()) continue;
            std::vector<std::uint32_t> primitives(stopped.primitive_indices().begin() + node.index,
                                                  stopped.primitive_indices().begin() + node.index + node.count);
            std::sort(primitives.begin(), primitives.end());
            leaves.push_back({node.bounds, std::move(primitives)});
        }
        std::sort(expected.begin(), expected.end());
        std::sort(leaves.begin(), leaves.end());
        REQUIRE(leaves.size() == expected.size());
        std::size_t different = 0;
        for (std::size_t i = 0; i < leaves.size(); ++i)
            different += leaves[i].primitives != expected[i].primitives || leaves[i].bounds.min != expected[i].bounds.min ||
                         leaves[i].bounds.max != expected[i].bounds.max;
        CHECK(different == 0);
    }
}

TEST_CASE_TEMPLATE("BVH built from a box function: the same trees as from an array of boxes", Real, float, double) {
    // TriangleMesh hands its boxes to the index as it makes them (build(count, box_of)); the
    // trees must be those of the array form, node for node. One thread: the parallel build
    // numbers nodes in the order its tasks run.
    const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    std::vector<glm::dvec3> positions;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    perturbed_sphere(5, 11, positions, triangles);  // 20,480 triangles: the large nodes' scratch too
    const auto boxes = triangle_boxes<Real>(positions, triangles);
    std::vector<std::uint32_t> asked;
    const auto box_of = [&](std::uint32_t i) {
        asked.push_back(i);
        return boxes[i];
    };
    const auto same_box = [](const prism::Aabb<Real>& a, const prism::Aabb<Real>& b) { return a.min == b.min && a.max == b.max; };
    {
        const auto from_array = prism::BvhTree<Real>::build(boxes);
        const auto from_function = prism::BvhTree<Real>::build(std::uint32_t(boxes.size()), box_of);
        std::vector<std::uint32_t> in_order(boxes.size());
        std::iota(in_order.begin(), in_order.end(), 0u);
        CHECK(asked == in_order);  // once each, in order
        REQUIRE(from_function.nodes().size() == from_array.nodes().size());
        std::size_t different = 0;
        for (std::size_t i = 0; i < from_array.nodes().size(); ++i) {
            const auto &a = from_array.nodes()[i], &b = from_function.nodes()[i];
            different += !same_box(a.bounds, b.bounds) || a.index != b.index || a.count != b.count;
        }
        CHECK(different == 0);
        CHECK(from_function.primitive_indices() == from_array.primitive_indices());
    }
    const auto check_wide = [&]<int N>(std::integral_constant<int, N>) {
        const auto from_array = prism::WideBvhTree<Real, N>::build(boxes);
        const auto from_function = prism::WideBvhTree<Real, N>::build(std::uint32_t(boxes.size()), box_of);
        check_same_wide_trees(from_array, from_function);
    };
    check_wide(std::integral_constant<int, 4>{});
    check_wide(std::integral_constant<int, 8>{});
}

TEST_CASE_TEMPLATE("BVH built on two threads: the same trees as on one", Real, float, double) {
    // Large nodes bin, partition and make their boxes in parallel runs merged in order, and the
    // collapse plans subtrees as tasks: the trees must be the one-thread trees. 81,920
    // triangles: the root and its children take the parallel passes (2 x 16,384 and more).
    std::vector<glm::dvec3> positions;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    perturbed_sphere(6, 13, positions, triangles);
    REQUIRE(triangles.size() >= 4 * 16384);
    const auto boxes = triangle_boxes<Real>(positions, triangles);
    const auto built_on = [&]<class Tree>(std::size_t threads, const Tree*) {
        const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        return Tree::build(boxes);
    };
    const auto same_box = [](const prism::Aabb<Real>& a, const prism::Aabb<Real>& b) {
        return std::memcmp(&a, &b, sizeof a) == 0;  // bit for bit, the sign of a zero included
    };
    {
        using Tree = prism::BvhTree<Real>;
        const Tree one = built_on(1, (const Tree*)nullptr), two = built_on(2, (const Tree*)nullptr);
        REQUIRE(one.nodes().size() == two.nodes().size());
        CHECK(one.primitive_indices() == two.primitive_indices());
        // Depth first: parallel tasks number the nodes in the order they run.
        std::vector<std::pair<std::uint32_t, std::uint32_t>> todo{{0, 0}};
        std::size_t different = 0, visited = 0;
        while (!todo.empty()) {
            const auto [i, j] = todo.back();
            todo.pop_back();
            const auto &a = one.nodes()[i], &b = two.nodes()[j];
            ++visited;
            different += !same_box(a.bounds, b.bounds) || a.count != b.count || (a.is_leaf() && a.index != b.index);
            if (!a.is_leaf() && !b.is_leaf()) {
                todo.push_back({a.index, b.index});
                todo.push_back({a.index + 1, b.index + 1});
            }
        }
        CHECK(visited == one.nodes().size());
        CHECK(different == 0);
    }
    const auto check_wide = [&]<int N>(std::integral_constant<int, N>) {
        using Tree = prism::WideBvhTree<Real, N>;
        check_same_wide_trees(built_on(1, (const Tree*)nullptr), built_on(2, (const Tree*)nullptr));
    };
    check_wide(std::integral_constant<int, 4>{});
    check_wide(std::integral_constant<int, 8>{});
}

TEST_CASE("HugePageAllocator: aligned for its type below and above a huge page, huge-page aligned above") {
    // The builder's boxes of double lanes ask for 32 bytes, more than operator new's default.
    struct alignas(32) Wide {
        double lanes[4];
    };
    for (const std::size_t count : {std::size_t(3), std::size_t(1000), std::size_t(200000)}) {
        CAPTURE(count);
        std::vector<Wide, prism::HugePageAllocator<Wide>> array(count);
        const auto address = reinterpret_cast<std::uintptr_t>(array.data());
        CHECK(address % alignof(Wide) == 0);
        if (count * sizeof(Wide) >= prism::HugePageAllocator<Wide>::huge_page)
            CHECK(address % prism::HugePageAllocator<Wide>::huge_page == 0);
        for (std::size_t i = 0; i < count; ++i) array[i].lanes[0] = double(i);  // every byte is ours
        CHECK(array[count - 1].lanes[0] == double(count - 1));
    }
}

TEST_CASE_TEMPLATE("BVH on no primitives: an empty tree, an empty mesh, an empty scene", Real, float, double) {
    const auto tree = prism::BvhTree<Real>::build({});
    check_structure(tree, {}, 8);
    CHECK(tree.bounds().is_empty());
    const prism::Ray<Real> ray{prism::Vec3<Real>(0), prism::Vec3<Real>(0, 0, -1), Real(0), prism::infinity<Real>};
    Real t_max = prism::infinity<Real>;
    bool leaf_called = false;
    tree.traverse_closest(ray, t_max, [&](std::uint32_t, std::uint32_t, Real&) { return leaf_called = true; });
    CHECK_FALSE(leaf_called);
    CHECK_FALSE(tree.traverse_any(ray, t_max, [&](std::uint32_t, std::uint32_t, Real&) { return true; }));

    scene::Scene nothing;
    scene::Scene empty_mesh;
    empty_mesh.materials.push_back({});
    empty_mesh.meshes.push_back({});
    empty_mesh.mesh_instances.push_back({"moved", 0, 0, glm::translate(glm::dmat4(1.0), glm::dvec3(1, 2, 3))});
    for (const scene::Scene* world : {&nothing, &empty_mesh}) {
        const BvhGeometry<Real> bvh(*world);
        const BruteGeometry<Real> brute(*world);
        CHECK(bvh.triangle_count() == 0);
        for (const prism::Vec3<Real> direction : {prism::Vec3<Real>(0, 0, -1), prism::Vec3<Real>(1, 2, 3)}) {
            prism::Ray<Real> a{prism::Vec3<Real>(0), direction, Real(0), prism::infinity<Real>}, b = a;
            prism::Hit<Real> hit;
            CHECK_FALSE(prism::closest_hit(bvh, a, hit));
            CHECK_FALSE(prism::closest_hit(brute, b, hit));
            CHECK(a.t_max == prism::infinity<Real>);
            CHECK_FALSE(prism::blocked(bvh, a));
            CHECK_FALSE(prism::blocked(brute, b));
        }
    }
}

// A single triangle is a single leaf whose box is the triangle's own: rays at its vertices and
// edges pass exactly through the box's corners and faces, where the slab test's rounding is
// tightest. The BVH must hit whenever the watertight test alone hits, at the same t.
TEST_CASE_TEMPLATE("BVH on one triangle: never culls a hit at a vertex or an edge", Real, float, double) {
    std::mt19937 random(64);
    std::uniform_real_distribution<double> uniform(-2.0, 2.0);
    std::size_t rays_tested = 0, direct_hits = 0, lost = 0, wrong_t = 0, invented = 0;
    for (int trial = 0; trial < 200; ++trial) {
        std::array<glm::dvec3, 3> triangle;
        for (auto& p : triangle) p = glm::dvec3(uniform(random), uniform(random), uniform(random));
        if (trial % 4 == 0) triangle[1].z = triangle[2].z = triangle[0].z;  // flat box, as for floors
        scene::Scene world;
        world.materials.push_back({});
        scene::Mesh mesh;
        mesh.positions = {triangle[0], triangle[1], triangle[2]};
        mesh.triangles = {{0, 1, 2}};
        world.meshes.push_back(mesh);
        const prism::Vec3<Real> p0(triangle[0]), p1(triangle[1]), p2(triangle[2]);
        const auto rays = rays_at_triangle<Real>(triangle, 400, random);
        for_each_bvh<Real>([&]<class Geometry>() {
        const Geometry bvh(world);
        for (const auto& ray : rays) {
            ++rays_tested;
            prism::TriangleHit<Real> direct;
            const prism::Watertight::Prepared<Real> prepared(ray);
            const bool expected = prism::Watertight::intersect(prepared, p0, p1, p2, ray.t_min, ray.t_max, direct);
            prism::Ray<Real> traced = ray;
            prism::Hit<Real> hit;
            const bool found = prism::closest_hit(bvh, traced, hit);
            direct_hits += expected ? 1 : 0;
            if (expected && !found) ++lost;
            if (!expected && found) ++invented;
            if (expected && found && hit.t != direct.t) ++wrong_t;
        }
        });
    }
    CHECK(direct_hits > rays_tested / 2);
    CHECK(lost == 0);
    CHECK(invented == 0);
    CHECK(wrong_t == 0);
}

// The case the random test found on the course's tap mesh (hw3 tap_tap.ply, triangle 1202): the
// ray passes exactly through the vertex at the box's (min x, max z) corner. The slab distances
// are x: [1.1019235232159181, ...] and z: [..., 1.1019235232159179], one ulp apart, so a slab
// test that does not widen each far distance culls the box, though the triangle is hit at
// t = 1.1019235232159181.
TEST_CASE("BvhTree<double>: the box of a triangle hit at its corner vertex is entered") {
    using V = prism::Vec3<double>;
    const V p0(-0.115581, -0.032274, 0.176249), p1(-0.131978, -0.044438, 0.176249), p2(-0.136777, -0.038591, 0.196117);
    const prism::Ray<double> ray{V(-1.057053199581486, -0.30807918077148766, -0.34674881023758808),
                                 V(0.83515432803875367, 0.2445616007769737, 0.49265289178441052), 0.0,
                                 prism::infinity<double>};
    prism::TriangleHit<double> direct;
    REQUIRE(prism::Watertight::intersect(prism::Watertight::Prepared<double>(ray), p0, p1, p2, 0.0,
                                         prism::infinity<double>, direct));
    CHECK(direct.t == 1.1019235232159181);
    prism::Aabb<double> box;
    for (const V& p : {p0, p1, p2}) box.extend(p);
    const auto tree = prism::BvhTree<double>::build(std::vector<prism::Aabb<double>>{box});
    double t_max = prism::infinity<double>;
    bool leaf_reached = false;
    tree.traverse_closest(ray, t_max, [&](std::uint32_t, std::uint32_t, double&) { return leaf_reached = true; });
    CHECK(leaf_reached);
}

TEST_CASE_TEMPLATE("BVH on many copies of one triangle: hits like brute force", Real, float, double) {
    scene::Scene world;
    world.materials.push_back({});
    scene::Mesh mesh;
    mesh.positions = {{-1, -1, -3}, {1, -1, -3}, {0, 1, -3}};
    for (int i = 0; i < 1000; ++i) mesh.triangles.push_back({0, 1, 2});
    world.meshes.push_back(mesh);
    for_each_bvh<Real>([&]<class Geometry>() {
    const Geometry bvh(world);
    const BruteGeometry<Real> brute(world);
    REQUIRE(bvh.triangle_count() == 1000);
    std::mt19937 random(3);
    std::uniform_real_distribution<double> uniform(-1.5, 1.5);
    std::size_t hits = 0, disagreements = 0;
    for (int i = 0; i < 2000; ++i) {
        const prism::Vec3<Real> target(Real(uniform(random)), Real(uniform(random)), Real(-3));
        const prism::Vec3<Real> origin(Real(uniform(random)), Real(uniform(random)), Real(1));
        prism::Ray<Real> a{origin, glm::normalize(target - origin), Real(0), prism::infinity<Real>}, b = a;
        prism::Hit<Real> hit_a, hit_b;
        const bool found_a = prism::closest_hit(bvh, a, hit_a), found_b = prism::closest_hit(brute, b, hit_b);
        hits += found_b ? 1 : 0;
        if (found_a != found_b || (found_a && hit_a.t != hit_b.t) || prism::blocked(bvh, prism::Ray<Real>{origin, a.direction}) != found_b)
            ++disagreements;
    }
    CHECK(hits > 300);
    CHECK(hits < 2000);
    CHECK(disagreements == 0);
    });
}

// SceneGeometry's contract: closest hit in (t_min, t_max], any hit in (t_min, t_max), for every
// kind of shape alike. A shadow ray towards a point on a surface (an area light's sample, say)
// has t_max at that surface and must not be blocked by it.
TEST_CASE_TEMPLATE("SceneGeometry: the hit interval is the same for triangles, spheres and planes", Real, float, double) {
    // Along -z from the origin: a triangle at z = -2, a sphere with its near side at z = -2, a
    // plane at z = -2; each alone in its scene, each hit at t = 2 exactly.
    scene::Scene triangle_scene, sphere_scene, plane_scene;
    for (scene::Scene* world : {&triangle_scene, &sphere_scene, &plane_scene}) world->materials.push_back({});
    scene::Mesh mesh;
    mesh.positions = {{-1, -1, -2}, {1, -1, -2}, {0, 1, -2}};
    mesh.triangles = {{0, 1, 2}};
    triangle_scene.meshes.push_back(mesh);
    sphere_scene.spheres.push_back({"ball", 0, {0, 0, -3}, 1.0, glm::dmat4(1.0)});
    plane_scene.planes.push_back({"wall", 0, {0, 0, -2}, {0, 0, 1}, glm::dmat4(1.0)});
    const std::array<std::pair<std::string, const scene::Scene*>, 3> cases{
        {{"triangle", &triangle_scene}, {"sphere", &sphere_scene}, {"plane", &plane_scene}}};
    for (const auto& shape_case : cases) {
        const std::string& shape = shape_case.first;
        const scene::Scene* const world = shape_case.second;
        CAPTURE(shape);
        for_each_bvh<Real>([&]<class Geometry>() {
        const Geometry geometry(*world);
        const prism::Ray<Real> ray{prism::Vec3<Real>(0), prism::Vec3<Real>(0, 0, -1), Real(0), prism::infinity<Real>};
        prism::Hit<Real> hit;
        prism::Ray<Real> closed = ray;
        closed.t_max = Real(2);
        REQUIRE(prism::closest_hit(geometry, closed, hit));
        CHECK(hit.t == Real(2));
        CHECK(closed.t_max == Real(2));
        prism::Ray<Real> short_ray = ray;
        short_ray.t_max = prism::next_down(Real(2));
        CHECK_FALSE(prism::closest_hit(geometry, short_ray, hit));
        prism::Ray<Real> past = ray;
        past.t_min = Real(2);
        past.t_max = Real(2.5);
        CHECK_FALSE(prism::closest_hit(geometry, past, hit));

        prism::Ray<Real> shadow = ray;
        shadow.t_max = prism::next_up(Real(2));
        CHECK(prism::blocked(geometry, shadow));
        shadow.t_max = Real(2);
        CHECK_FALSE(prism::blocked(geometry, shadow));  // open at t_max: fails for the triangle today
        });
    }
}

TEST_CASE_TEMPLATE("SceneGeometry: back-face culling skips surfaces facing away, only when asked", Real, float, double) {
    using prism::BackfaceCulling;
    scene::Scene world;
    world.materials.push_back({});
    scene::Mesh mesh;  // counter-clockwise seen from +z: faces +z
    mesh.positions = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 2}};
    world.meshes.push_back(mesh);
    world.planes.push_back({"floor", 0, {0, 0, -5}, {0, 0, 1}, glm::dmat4(1.0)});
    for_each_bvh<Real>([&]<class Geometry>() {
    const Geometry geometry(world);
    const prism::Ray<Real> from_front{prism::Vec3<Real>(0, 0, 2), prism::Vec3<Real>(0, 0, -1)};
    const prism::Ray<Real> from_behind{prism::Vec3<Real>(0, 0, -10), prism::Vec3<Real>(0, 0, 1)};
    prism::Hit<Real> hit;
    prism::Ray<Real> ray = from_front;
    REQUIRE(prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::all));
    CHECK(hit.t == Real(2));
    CHECK(hit.object == 0);
    ray = from_behind;
    CHECK_FALSE(prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::all));  // both the plane and the triangle face away
    ray = from_behind;
    REQUIRE(prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::none));
    CHECK(hit.t == Real(5));
    CHECK(hit.object == 1);  // planes are numbered after the instances
    ray = from_behind;
    ray.t_min = Real(6);
    REQUIRE(prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::none));
    CHECK(hit.t == Real(10));
    CHECK(hit.object == 0);
    // The course's rule skips the flat triangle but keeps the plane.
    ray = from_behind;
    ray.t_min = Real(6);
    CHECK_FALSE(prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::triangles));
    ray = from_behind;
    REQUIRE(prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::triangles));
    CHECK(hit.object == 1);
    });
}

TEST_CASE_TEMPLATE("SceneGeometry: the course's culling skips smooth meshes too and follows instances' transformations",
                   Real, float, double) {
    using prism::BackfaceCulling;
    scene::Scene world;
    world.materials.push_back({});
    scene::Mesh flat;  // faces +z, at z = 0
    flat.positions = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
    flat.triangles = {{0, 1, 2}};
    scene::Mesh smooth = flat;  // the same triangle at z = -1, smooth-shaded
    smooth.shading = scene::ShadingMode::smooth;
    for (auto& p : smooth.positions) p.z = -1;
    world.meshes = {flat, smooth};
    const prism::Ray<Real> from_behind{prism::Vec3<Real>(0, 0, -10), prism::Vec3<Real>(0, 0, 1)};
    const prism::Ray<Real> from_front{prism::Vec3<Real>(0, 0, 10), prism::Vec3<Real>(0, 0, -1)};
    prism::Hit<Real> hit;
    {
        const BvhGeometry<Real> geometry(world);
        prism::Ray<Real> ray = from_behind;
        // From behind both triangles face away: the smooth one (t = 9) is skipped as the flat
        // one is; without culling it is met first.
        CHECK_FALSE(prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::triangles));
        ray = from_behind;
        CHECK_FALSE(prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::all));
        ray = from_behind;
        REQUIRE(prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::none));
        CHECK(hit.t == Real(9));
        CHECK(hit.object == 1);
        // From the front, nothing is culled: the flat triangle at t = 10 is nearer.
        ray = from_front;
        REQUIRE(prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::triangles));
        CHECK(hit.t == Real(10));
        CHECK(hit.object == 0);
    }
    // An instance turned half around the y axis and moved to z = 1 faces -z: culled from the
    // front, seen from behind, while the original at z = 0 (facing +z) does the opposite.
    world.meshes.pop_back();
    const glm::dmat4 turned = glm::translate(glm::dmat4(1.0), glm::dvec3(0, 0, 1)) *
                              glm::rotate(glm::dmat4(1.0), 3.141592653589793, glm::dvec3(0, 1, 0));
    world.mesh_instances.push_back({"turned", 0, 0, turned, {}, {}});
    const BvhGeometry<Real> geometry(world);
    prism::Ray<Real> ray = from_behind;
    REQUIRE(prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::triangles));
    CHECK(hit.t == doctest::Approx(11).epsilon(1e-6));
    ray = from_front;
    REQUIRE(prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::triangles));
    CHECK(hit.t == doctest::Approx(10).epsilon(1e-6));
    ray = from_front;
    REQUIRE(prism::closest_hit(geometry, ray, hit, prism::BackfaceCulling::none));
    CHECK(hit.t == doctest::Approx(9).epsilon(1e-6));
}

// ---------------------------------------------------------------------------------------------
// The wide BVH's structure

namespace {

// Every primitive in exactly one leaf, each leaf's range starting at a multiple of N and padded
// with repeats of its last primitive, children inside their parent, leaves around their
// primitives, every node reached once, empty child slots missed by every ray.
template <class Real, int N>
void check_wide_structure(const prism::WideBvhTree<Real, N>& tree, const std::vector<prism::Aabb<Real>>& boxes) {
    const auto& nodes = tree.nodes();
    const auto& order = tree.primitive_indices();
    CHECK(order.size() % N == 0);
    if (boxes.empty()) {
        CHECK(nodes.empty());
        return;
    }
    std::vector<int> listed(boxes.size(), 0), node_visits(nodes.size(), 0);
    std::size_t misaligned = 0, bad_padding = 0, primitive_outside = 0, child_outside = 0, empty_slots = 0;
    std::vector<std::pair<std::uint32_t, prism::Aabb<Real>>> stack{{0u, tree.bounds()}};
    while (!stack.empty()) {
        const auto [index, parent_box] = stack.back();
        stack.pop_back();
        REQUIRE(index < nodes.size());
        ++node_visits[index];
        const auto& node = nodes[index];
        for (int c = 0; c < N; ++c) {
            prism::Aabb<Real> box;
            for (int axis = 0; axis < 3; ++axis) {
                box.min[axis] = node.bounds[axis][c];
                box.max[axis] = node.bounds[3 + axis][c];
            }
            if (box.is_empty()) {
                ++empty_slots;
                continue;
            }
            if (!encloses(parent_box, box)) ++child_outside;
            if (node.count(c) == 0) {
                stack.push_back({node.index(c), box});
                continue;
            }
            const std::uint32_t first = node.index(c), count = node.count(c);
            if (first % N != 0) ++misaligned;
            REQUIRE(first + count <= order.size());
            for (std::uint32_t slot = first; slot < first + count; ++slot) {
                ++listed[order[slot]];
                if (!encloses(box, boxes[order[slot]])) ++primitive_outside;
            }
            for (std::uint32_t slot = first + count; slot % N != 0; ++slot)
                if (order[slot] != order[first + count - 1]) ++bad_padding;
        }
    }
    CHECK(std::count(listed.begin(), listed.end(), 1) == std::ptrdiff_t(boxes.size()));
    CHECK(std::count(node_visits.begin(), node_visits.end(), 1) == std::ptrdiff_t(nodes.size()));
    CHECK(misaligned == 0);
    CHECK(bad_padding == 0);
    CHECK(primitive_outside == 0);
    CHECK(child_outside == 0);
    // The empty slots are missed, even by rays of unbounded length along and against each axis.
    if (empty_slots > 0) {
        std::size_t entered = 0;
        for (int axis = 0; axis < 3; ++axis)
            for (Real sign : {Real(1), Real(-1), Real(0)}) {
                prism::Vec3<Real> direction(Real(0.25));
                direction[axis] = sign;
                const prism::Ray<Real> ray{tree.bounds().centroid(), direction, Real(0), prism::infinity<Real>};
                // Entering an empty slot would re-enter the root: more leaves than there are.
                std::size_t leaves = 0;
                if (tree.traverse_any(ray, prism::infinity<Real>,
                                      [&](std::uint32_t, std::uint32_t, Real&) { return ++leaves > order.size(); }))
                    ++entered;
            }
        CHECK(entered == 0);
    }
}

template <class Real, int N>
void check_wide_trees() {
    std::vector<glm::dvec3> positions;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    perturbed_sphere(4, 11, positions, triangles);
    const auto sphere_boxes = triangle_boxes<Real>(positions, triangles);
    check_wide_structure(prism::WideBvhTree<Real, N>::build(sphere_boxes), sphere_boxes);
    std::vector<prism::Aabb<Real>> one_centre(1000, prism::Aabb<Real>{prism::Vec3<Real>(-1), prism::Vec3<Real>(1)});
    check_wide_structure(prism::WideBvhTree<Real, N>::build(one_centre), one_centre);
    for (std::size_t count : {0, 1, 3, N + 1}) {
        const std::vector<prism::Aabb<Real>> few(sphere_boxes.begin(), sphere_boxes.begin() + std::ptrdiff_t(count));
        check_wide_structure(prism::WideBvhTree<Real, N>::build(few), few);
    }
    // The heuristic collapse: a leaf holds at most two packets, and nodes are nearly full (the
    // largest-area collapse left the tiny-triangle dragon's 8-wide nodes with 4.3 children).
    {
        const auto tree = prism::WideBvhTree<Real, N>::build(sphere_boxes);
        std::uint32_t largest = 0;
        std::size_t children = 0;
        for (const auto& node : tree.nodes())
            for (int c = 0; c < N; ++c) {
                largest = std::max(largest, node.count(c));
                children += node.bounds[0][c] <= node.bounds[3][c] ? 1 : 0;
            }
        CHECK(largest <= 2 * N);
        CHECK(double(children) / double(tree.nodes().size()) > 0.8 * N);
    }
    // Smaller leaves on request (a scene's top level asks for one instance per leaf); a larger
    // request is held to N, the width of the triangle packets.
    for (const std::uint32_t max_leaf_size : {1u, 3u}) {
        prism::BvhBuildOptions options;
        options.max_leaf_size = max_leaf_size;
        for (const std::vector<prism::Aabb<Real>>* input : {&sphere_boxes, &std::as_const(one_centre)}) {
            const auto tree = prism::WideBvhTree<Real, N>::build(*input, options);
            check_wide_structure(tree, *input);
            std::uint32_t largest = 0;
            for (const auto& node : tree.nodes())
                for (int c = 0; c < N; ++c) largest = std::max(largest, node.count(c));
            CHECK(largest >= 1);
            CHECK(largest <= max_leaf_size);
        }
    }
    prism::BvhBuildOptions too_large;
    too_large.max_leaf_size = 1000;
    const auto held = prism::WideBvhTree<Real, N>::build(sphere_boxes, too_large);
    const auto standard = prism::WideBvhTree<Real, N>::build(sphere_boxes);
    CHECK(held.nodes().size() == standard.nodes().size());
    CHECK(held.primitive_indices() == standard.primitive_indices());
    // The geometric progression drives the binary build to its depth cap, leaving leaves of
    // more than N primitives: traversal must still reach every one of them.
    std::vector<prism::Aabb<Real>> boxes;
    const int count = std::is_same_v<Real, float> ? 120 : 1000;
    for (int i = 0; i < count; ++i) {
        const Real x = std::ldexp(Real(1), -i);
        boxes.push_back({prism::Vec3<Real>(x, 0, 0), prism::Vec3<Real>(x + x / 2, x / 2, x / 2)});
    }
    const auto tree = prism::WideBvhTree<Real, N>::build(boxes);
    check_wide_structure(tree, boxes);
    const auto& order = tree.primitive_indices();
    std::size_t unreached = 0;
    for (int i = 0; i < count; ++i) {
        const Real x = std::ldexp(Real(1), -i);
        const prism::Ray<Real> ray{prism::Vec3<Real>(x + x / 4, x / 4, 1), prism::Vec3<Real>(0, 0, -1), Real(0),
                                   prism::infinity<Real>};
        const bool reached = tree.traverse_any(ray, prism::infinity<Real>, [&](std::uint32_t first, std::uint32_t n, Real&) {
            return std::find(order.begin() + first, order.begin() + first + n, std::uint32_t(i)) != order.begin() + first + n;
        });
        unreached += reached ? 0 : 1;
    }
    CHECK(unreached == 0);
}

}  // namespace

TEST_CASE_TEMPLATE("Wide BVH structure (4 and 8 children): a mesh, one centroid, tiny inputs, a deep progression", Real,
                   float, double) {
    check_wide_trees<Real, 4>();
    check_wide_trees<Real, 8>();
}

namespace {

// The leaves a traversal visits, in order, with the t_max each saw: a leaf "hits" at 0.9 of
// its t_max every third call, so the sequence also depends on how t_max prunes the rest.
template <class Real>
struct LeafLog {
    std::vector<std::array<double, 3>> visits;  // first, count, t_max on entry
    int calls = 0;
    auto closest() {
        return [this](std::uint32_t first, std::uint32_t count, Real& t_max) {
            visits.push_back({double(first), double(count), double(t_max)});
            if (++calls % 3 != 0) return false;
            t_max = std::isinf(t_max) ? Real(50) : Real(0.9) * t_max;
            return true;
        };
    }
};

// A ray prepared once (Index::TraversalRay, what SceneGeometry shares between the top level and
// the meshes in world space) must traverse exactly as the ray itself.
template <class Index, class Real>
void check_prepared_traversal(const std::vector<prism::Aabb<Real>>& boxes, const std::vector<prism::Ray<Real>>& rays) {
    const Index index = Index::build(boxes);
    std::size_t closest_differ = 0, any_differ = 0;
    for (const prism::Ray<Real>& ray : rays) {
        LeafLog<Real> own, shared;
        Real t_own = ray.t_max, t_shared = ray.t_max;
        index.traverse_closest(ray, t_own, own.closest());
        const typename Index::TraversalRay prepared(ray);
        index.traverse_closest(prepared, ray.t_min, t_shared, shared.closest());
        closest_differ += own.visits != shared.visits || t_own != t_shared;
        const auto any = [](std::uint32_t first, std::uint32_t, Real&) { return first % 2 == 1; };
        any_differ += index.traverse_any(ray, ray.t_max, any) != index.traverse_any(prepared, ray.t_min, ray.t_max, any);
    }
    CHECK(closest_differ == 0);
    CHECK(any_differ == 0);
}

}  // namespace

TEST_CASE_TEMPLATE("Indices: a ray prepared once traverses exactly as the ray itself", Real, float, double) {
    std::vector<glm::dvec3> positions;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    perturbed_sphere(3, 17, positions, triangles);
    const auto boxes = triangle_boxes<Real>(positions, triangles);
    const auto rays = test_rays<Real>(bounds_of(positions), positions, 2000, 41);
    check_prepared_traversal<prism::BvhTree<Real>>(boxes, rays);
    check_prepared_traversal<prism::WideBvhTree<Real, 4>>(boxes, rays);
    check_prepared_traversal<prism::WideBvhTree<Real, 8>>(boxes, rays);
    check_prepared_traversal<prism::PrimitiveList<Real>>(boxes, rays);
}

namespace {

// The boxes of a perturbed icosphere's triangles (three subdivisions) and 2000 test rays
// around it: what the traversal-only checks below run on.
template <class Real>
std::pair<std::vector<prism::Aabb<Real>>, std::vector<prism::Ray<Real>>> sphere_boxes_and_rays(std::uint32_t mesh_seed,
                                                                                              std::uint32_t ray_seed) {
    std::vector<glm::dvec3> positions;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    perturbed_sphere(3, mesh_seed, positions, triangles);
    return {triangle_boxes<Real>(positions, triangles), test_rays<Real>(bounds_of(positions), positions, 2000, ray_seed)};
}

// The touch callback (a wide BVH prefetching the leaves it pushes) is a hint: traversal with it
// visits the same leaves in the same order with the same t_max, and it only ever names leaves.
template <class Real, int N>
void check_touched_traversal(const std::vector<prism::Aabb<Real>>& boxes, const std::vector<prism::Ray<Real>>& rays) {
    const auto tree = prism::WideBvhTree<Real, N>::build(boxes);
    std::set<std::uint32_t> leaf_starts;
    for (const auto& node : tree.nodes())
        for (int i = 0; i < N; ++i)
            if (node.count(i) != 0) leaf_starts.insert(node.index(i));
    std::size_t closest_differ = 0, any_differ = 0, touched = 0, not_leaves = 0;
    const auto touch = [&](std::uint32_t first) {
        ++touched;
        not_leaves += leaf_starts.count(first) == 0;
    };
    for (const prism::Ray<Real>& ray : rays) {
        const typename prism::WideBvhTree<Real, N>::TraversalRay prepared(ray);
        LeafLog<Real> plain, touching;
        Real t_plain = ray.t_max, t_touching = ray.t_max;
        tree.traverse_closest(prepared, ray.t_min, t_plain, plain.closest());
        tree.traverse_closest(prepared, ray.t_min, t_touching, touching.closest(), touch);
        closest_differ += plain.visits != touching.visits || t_plain != t_touching;
        const auto any = [](std::uint32_t first, std::uint32_t, Real&) { return first % 2 == 1; };
        any_differ += tree.traverse_any(prepared, ray.t_min, ray.t_max, any) !=
                      tree.traverse_any(prepared, ray.t_min, ray.t_max, any, touch);
    }
    CHECK(closest_differ == 0);
    CHECK(any_differ == 0);
    CHECK(touched > 0);
    CHECK(not_leaves == 0);
}

}  // namespace

TEST_CASE_TEMPLATE("Wide BVH: prefetching pushed leaves changes nothing of the traversal", Real, float, double) {
    const auto [boxes, rays] = sphere_boxes_and_rays<Real>(19, 43);
    check_touched_traversal<Real, 4>(boxes, rays);
    check_touched_traversal<Real, 8>(boxes, rays);
}

namespace {

// WideBvhTree::enters, the root's test that SceneGeometry makes before it prepares a world-space
// index's triangle set-up: a ray it turns away must visit no leaf, closest or any hit; and the
// rays of the test miss the tree often enough that turning none away would fail.
template <class Real, int N>
void check_root_test(const std::vector<prism::Aabb<Real>>& boxes, const std::vector<prism::Ray<Real>>& rays) {
    const auto tree = prism::WideBvhTree<Real, N>::build(boxes);
    std::size_t turned_away = 0, visited_anyway = 0, entered_and_visited = 0;
    for (const prism::Ray<Real>& ray : rays) {
        const typename prism::WideBvhTree<Real, N>::TraversalRay prepared(ray);
        LeafLog<Real> log;
        Real t_max = ray.t_max;
        tree.traverse_closest(prepared, ray.t_min, t_max, log.closest());
        bool any_visit = false;
        tree.traverse_any(prepared, ray.t_min, ray.t_max, [&](std::uint32_t, std::uint32_t, Real&) {
            any_visit = true;
            return false;
        });
        if (tree.enters(prepared, ray.t_min, ray.t_max)) {
            entered_and_visited += !log.visits.empty();
        } else {
            ++turned_away;
            visited_anyway += !log.visits.empty() || any_visit;
        }
    }
    CHECK(visited_anyway == 0);
    CHECK(turned_away > 0);
    CHECK(entered_and_visited > 0);
}

}  // namespace

TEST_CASE_TEMPLATE("Wide BVH: a ray the root's test turns away visits no leaf", Real, float, double) {
    const auto [boxes, rays] = sphere_boxes_and_rays<Real>(29, 47);
    check_root_test<Real, 4>(boxes, rays);
    check_root_test<Real, 8>(boxes, rays);
    CHECK(!prism::WideBvhTree<Real, 8>().enters(typename prism::WideBvhTree<Real, 8>::TraversalRay(rays[0]), Real(0),
                                               prism::infinity<Real>));
}

TEST_CASE_TEMPLATE("TriangleMesh: the caller's shared ray set-up finds the hits of the mesh's own", Real, float, double) {
    std::vector<glm::dvec3> positions;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    perturbed_sphere(3, 23, positions, triangles);
    const scene::Mesh mesh = soup_with_triangle_ids(positions, triangles);
    const auto rays = test_rays<Real>(bounds_of(positions), positions, 5000, 7);
    const auto check = [&]<class Policy>() {
        const prism::TriangleMesh<Real, Policy> triangle_mesh(mesh);
        using Mesh = prism::TriangleMesh<Real, Policy>;
        std::size_t hits = 0, differ = 0;
        for (const prism::Ray<Real>& ray : rays) {
            prism::Hit<Real> own_hit, shared_hit;
            Real t_own = ray.t_max, t_shared = ray.t_max;
            const typename Mesh::TraversalRay traversal_ray(ray);
            const typename Mesh::TriangleRay triangle_ray(ray);
            const bool own = triangle_mesh.intersect(ray, t_own, own_hit, false);
            const bool shared = triangle_mesh.intersect(ray, traversal_ray, triangle_ray, t_shared, shared_hit, false);
            hits += own;
            differ += own != shared || t_own != t_shared ||
                      (own && (own_hit.primitive != shared_hit.primitive || own_hit.b1 != shared_hit.b1 ||
                               own_hit.b2 != shared_hit.b2));
            differ += triangle_mesh.occluded(ray, ray.t_max) !=
                      triangle_mesh.occluded(ray, traversal_ray, triangle_ray, ray.t_max);
        }
        CHECK(hits > rays.size() / 2);
        CHECK(differ == 0);
    };
    check.template operator()<prism::Bvh<prism::Watertight>>();
    check.template operator()<prism::WideBvh<prism::Watertight, 4>>();
    check.template operator()<prism::WideBvh<prism::Watertight, 8>>();
    check.template operator()<prism::WideBvh<prism::DoubleRefine, 8>>();
    check.template operator()<prism::BruteForce<prism::Watertight>>();
}

namespace {

// WideBvhTree::from_layout, how the intersect bench runs the kernel on trees from other builders
// (Embree's): a tree's own layout, adopted, traverses exactly as the tree; and a layout build()
// never makes (every node's slots mirrored) finds the same nearest box along every ray and the
// same any-hit answers, so traversal reads the layout it is given, in whatever slot order.
template <class Real, int N>
void check_tree_from_layout(const std::vector<prism::Aabb<Real>>& boxes, const std::vector<prism::Ray<Real>>& rays) {
    using Tree = prism::WideBvhTree<Real, N>;
    const Tree built = Tree::build(boxes);
    const Tree adopted = Tree::from_layout(built.nodes(), built.primitive_indices(), built.bounds());
    std::vector<prism::WideBvhNode<Real, N>> nodes(built.nodes().begin(), built.nodes().end());
    for (auto& node : nodes) {
        for (int i = 0; i < N / 2; ++i) {
            for (auto& row : node.bounds) std::swap(row[i], row[N - 1 - i]);
            std::swap(node.child[i], node.child[N - 1 - i]);
        }
    }
    const Tree mirrored = Tree::from_layout(nodes, built.primitive_indices(), built.bounds());
    CHECK(mirrored.nodes().size() == built.nodes().size());
    CHECK(mirrored.nodes()[0].child[N - 1] == built.nodes()[0].child[0]);
    CHECK(mirrored.bounds().min == built.bounds().min);
    CHECK(mirrored.bounds().max == built.bounds().max);
    std::size_t adopted_differ = 0, nearest_differ = 0, any_differ = 0, hits = 0;
    for (const prism::Ray<Real>& ray : rays) {
        LeafLog<Real> own, adopted_log;
        Real t_own = ray.t_max, t_adopted = ray.t_max;
        built.traverse_closest(ray, t_own, own.closest());
        adopted.traverse_closest(ray, t_adopted, adopted_log.closest());
        adopted_differ += own.visits != adopted_log.visits || t_own != t_adopted;
        // The nearest primitive box the ray enters: the same whatever order the leaves come in.
        const prism::RayBoxPrecomputed<Real> box_ray(ray);
        const auto nearest_box = [&](const Tree& tree) {
            Real t_max = ray.t_max;
            tree.traverse_closest(ray, t_max, [&](std::uint32_t first, std::uint32_t count, Real& t_limit) {
                bool found = false;
                for (std::uint32_t slot = first; slot < first + count; ++slot) {
                    const Real entry = prism::intersect_box(boxes[tree.primitive_indices()[slot]], box_ray, ray.t_min, t_limit,
                                                            prism::robust_far_scale<Real>);
                    if (entry < t_limit) {
                        t_limit = entry;
                        found = true;
                    }
                }
                return found;
            });
            return t_max;
        };
        const Real nearest = nearest_box(built);
        nearest_differ += nearest != nearest_box(mirrored);
        hits += nearest != ray.t_max;
        const auto any = [](std::uint32_t first, std::uint32_t, Real&) { return first % 2 == 1; };
        any_differ += built.traverse_any(ray, ray.t_max, any) != mirrored.traverse_any(ray, ray.t_max, any);
    }
    CHECK(adopted_differ == 0);
    CHECK(nearest_differ == 0);
    CHECK(any_differ == 0);
    CHECK(hits > 0);
}

}  // namespace

TEST_CASE_TEMPLATE("Wide BVH from a given layout: traverses the layout it is given", Real, float, double) {
    const auto [boxes, rays] = sphere_boxes_and_rays<Real>(31, 53);
    check_tree_from_layout<Real, 4>(boxes, rays);
    check_tree_from_layout<Real, 8>(boxes, rays);
}

template <class Real, int N>
void check_child_words() {
    using Node = prism::WideBvhNode<Real, N>;
    Node node{};
    // Inner children: the node's index back, no count; the word is the node's byte offset.
    node.set_inner(0, 1);
    node.set_inner(1, 12345);
    CHECK(node.count(0) == 0);
    CHECK(node.index(0) == 1);
    CHECK(node.child[0] == sizeof(Node));
    CHECK(node.index(1) == 12345);
    // Leaves: first slot and count back, for leaves of one and two packets.
    for (std::uint32_t count = 1; count <= 2 * N; ++count) {
        node.set_leaf(2, 8 * count, count);
        CHECK(node.count(2) == count);
        CHECK(node.index(2) == 8 * count);
    }
    // The whole range of slots and node indices, and counts beyond a packet's (a leaf of
    // equal boxes is not split).
    node.set_leaf(3, UINT32_MAX, 1000);
    CHECK(node.index(3) == UINT32_MAX);
    CHECK(node.count(3) == 1000);
    node.set_inner(0, UINT32_MAX);
    CHECK(node.index(0) == UINT32_MAX);
    CHECK(node.count(0) == 0);
    CHECK_THROWS_AS(node.set_leaf(3, 0, 0), std::length_error);
    // The earlier slots are untouched by the later ones.
    CHECK(node.index(1) == 12345);
    CHECK(node.count(1) == 0);
}

TEST_CASE_TEMPLATE("Wide BVH node: one word per child, inner nodes and leaves read back", Real, float, double) {
    check_child_words<Real, 4>();
    check_child_words<Real, 8>();
}

namespace {

// The slab test's special cases (WideBvhTree::enter): rays parallel to an axis, with +0 and -0
// in their other components (infinite reciprocals, 0 * inf = NaN distances for an origin on a
// plane), starting inside, outside and exactly on the boxes' face planes. Each must
// visit every leaf whose box it meets (closed boxes, exactly: a ray parallel to the axis meets
// the box when its other two coordinates lie within the box's), and traversal must end (an
// empty slot, word 0, entered would lead back to the root for ever).
template <class Real, int N>
void check_axis_parallel_rays(int box_count) {
    std::vector<prism::Aabb<Real>> boxes;
    for (int i = 0; i < box_count; ++i) {
        const Real x = Real(i % 5) - Real(2), y = Real((i / 5) % 5) - Real(2), z = Real(i / 25) - Real(1);
        prism::Aabb<Real> box;
        box.extend(prism::Vec3<Real>(x, y, z));
        box.extend(prism::Vec3<Real>(x + Real(0.5), y + Real(1), z + Real(0.25)));
        boxes.push_back(box);
    }
    const auto tree = prism::WideBvhTree<Real, N>::build(boxes);
    const Real coordinates[] = {Real(-3), Real(-2), Real(-1.5), Real(-0.0), Real(0), Real(0.5), Real(0.75), Real(1), Real(2.5)};
    const Real zeros[] = {Real(0), Real(-0.0)};
    std::size_t rays = 0, hits = 0;
    for (int axis = 0; axis < 3; ++axis)
        for (const Real sign : {Real(1), Real(-1)})
            for (const Real zero : zeros)
                for (const Real a : coordinates)
                    for (const Real b : coordinates)
                        for (const Real along : {Real(-4), Real(0), Real(4)}) {
                            prism::Ray<Real> ray;
                            ray.direction = prism::Vec3<Real>(zero);
                            ray.direction[axis] = sign;
                            ray.origin[axis] = along;
                            ray.origin[(axis + 1) % 3] = a;
                            ray.origin[(axis + 2) % 3] = b;
                            std::set<std::uint32_t> expected;
                            for (std::uint32_t i = 0; i < boxes.size(); ++i) {
                                const prism::Aabb<Real>& box = boxes[i];
                                bool meets = true;
                                for (int other = 1; other < 3; ++other) {
                                    const int k = (axis + other) % 3;
                                    meets &= box.min[k] <= ray.origin[k] && ray.origin[k] <= box.max[k];
                                }
                                // Ahead of the origin (t_min = 0): the box's far side along the axis.
                                const Real far_side = sign > 0 ? box.max[axis] : box.min[axis];
                                meets &= sign > 0 ? far_side >= along : far_side <= along;
                                if (meets) expected.insert(i);
                            }
                            std::set<std::uint32_t> visited;
                            Real t_max = ray.t_max;
                            tree.traverse_closest(ray, t_max, [&](std::uint32_t first, std::uint32_t count, Real&) {
                                for (std::uint32_t slot = first; slot < first + count; ++slot)
                                    visited.insert(tree.primitive_indices()[slot]);
                                return false;
                            });
                            CAPTURE(axis);
                            CAPTURE(sign);
                            CAPTURE(a);
                            CAPTURE(b);
                            CAPTURE(along);
                            CHECK(std::includes(visited.begin(), visited.end(), expected.begin(), expected.end()));
                            ++rays;
                            hits += !expected.empty();
                        }
    CHECK(hits > 0);  // some rays meet boxes (60 of 2,916 meet the three boxes)
}

}  // namespace

TEST_CASE_TEMPLATE("Wide BVH: rays parallel to an axis, on and off the boxes' planes, visit every box they meet", Real, float,
                   double) {
    for (const int box_count : {3, 75}) {
        check_axis_parallel_rays<Real, 4>(box_count);
        check_axis_parallel_rays<Real, 8>(box_count);
    }
}
