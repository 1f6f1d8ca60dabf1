// Intersection benchmarks (Google Benchmark). Every triangle intersector (NaiveEpsilon,
// Watertight, DoubleRefine) in float and double traces the same ray batches (primary, shadow,
// diffuse) over two workloads: the largest hw1 course scene and the tiny-triangle dragon
// (dragon_lowres subdivided to 766,144 triangles, made in process by prism/scene/stress.hpp);
// Embree 3 traces them too when it is installed (PRISM_BENCH_WITH_EMBREE). The wide BVH
// (WideBvh, 4 and 8 children) runs Watertight in float and double and DoubleRefine, and the
// renderer's own choices run as default_float, default_double and default_double_refine. Also:
// BVH build times, and paired time ratios between variants that stand up to a shared, noisy
// machine.
//
// Every ray benchmark checks its answers: hit or miss (occluded or not, for shadow rays) per ray
// against a double-precision Watertight reference computed once; robust variants that disagree
// on more than `allowed_mismatch_fraction` of the rays stop with an error (tinybvh's lesson: a
// benchmark that does not check its result measures nothing). Rays are traced one at a time on
// one thread, so the ratios compare algorithms, not parallel scaling. After the run, a summary
// prints this run's ratios, rays per second and answers. See bench/RESULTS.md.
#include <prism/camera/pinhole_camera.hpp>
#include <prism/geometry/double_refine.hpp>
#include <prism/geometry/naive_epsilon.hpp>
#include <prism/geometry/scene_geometry.hpp>
#include <prism/geometry/watertight.hpp>
#include <prism/io/load.hpp>
#include <prism/render/render_scene.hpp>
#include <prism/scene/stress.hpp>

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#ifdef PRISM_BENCH_WITH_EMBREE
#include <prism/accel/embree.hpp>

#include <embree3/rtcore.h>
#endif

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <time.h>

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif

namespace {

namespace fs = std::filesystem;
namespace scene = prism::scene;
using prism::Ray;
using prism::Vec3;

// ---------------------------------------------------------------------------------------------
// Workloads and their ray batches

constexpr std::size_t primary_ray_target = 1 << 17;  // camera rays per batch (about 131,000)

// Far above the rounding of an origin to float (half an ulp of its largest coordinate) and of
// the watertight test's own error in t, far below the triangles' size (the dragon's edges are
// about 2e-3 of its coordinates): 256 float ulps of the hit point's largest coordinate.
// Hit points near the origin use 1% of the scene's radius as their magnitude instead.
double origin_offset(const glm::dvec3& point, double scene_radius) {
    const double magnitude = std::max({std::abs(point.x), std::abs(point.y), std::abs(point.z), 1e-2 * scene_radius});
    return 0x1p-16 * magnitude;
}

enum class BatchKind { primary, shadow, diffuse };
constexpr std::array batch_kinds{BatchKind::primary, BatchKind::shadow, BatchKind::diffuse};

const char* batch_name(BatchKind kind) {
    switch (kind) {
        case BatchKind::primary: return "primary";
        case BatchKind::shadow: return "shadow";
        case BatchKind::diffuse: return "diffuse";
    }
    return "?";
}

struct RayBatch {
    bool any_hit = false;                 // shadow rays ask occluded(); the others the closest hit
    std::vector<Ray<double>> rays;        // every value exactly representable in float...
    std::vector<Ray<float>> rays_float;   // ...so these are the same rays
    std::vector<std::uint8_t> reference;  // hit (occluded) per ray, by double-precision Watertight

    template <class Real>
    const std::vector<Ray<Real>>& rays_in() const {
        if constexpr (std::is_same_v<Real, float>) return rays_float;
        else return rays;
    }
};

struct Workload {
    std::string name;
    std::string error;  // why the workload could not be made (course data missing); empty if made
    scene::Scene scene; // meshes only (no spheres, planes or instances), one camera, one light
    std::size_t triangle_count = 0;
    std::array<RayBatch, 3> batches;
};

using ReferenceGeometry = prism::SceneGeometry<double, prism::Bvh<prism::Watertight>>;

template <class Real, class Policy>
const prism::SceneGeometry<Real, Policy>& geometry_of(const Workload& workload) {
    using Geometry = prism::SceneGeometry<Real, Policy>;
    static std::map<const Workload*, std::unique_ptr<Geometry>> cache;
    std::unique_ptr<Geometry>& slot = cache[&workload];
    if (!slot) slot = std::make_unique<Geometry>(workload.scene);
    return *slot;
}

// Rounds to float and back through a volatile: without it, GCC 12.2 at -O3 compiled the primary
// rays' Vec3<double>(Vec3<float>(direction)) into a copy of the doubles (its SLP vectorizer drops
// the double(float(x)) pair, as in tests/test_leaks.cpp), and check_same_rays found all 131,044
// primary rays of each workload unrounded in y and z.
double through_float(double value) {
    const volatile float rounded = float(value);
    return double(rounded);
}

Vec3<double> through_float(const Vec3<double>& v) { return {through_float(v.x), through_float(v.y), through_float(v.z)}; }

Ray<double> representable_in_float(const Ray<double>& ray) {
    return {through_float(ray.origin), through_float(ray.direction), through_float(ray.t_min), through_float(ray.t_max)};
}

Ray<float> to_float(const Ray<double>& ray) {
    return {Vec3<float>(ray.origin), Vec3<float>(ray.direction), float(ray.t_min), float(ray.t_max)};
}

// The float and double batches must hold the same rays, or float and double variants would be
// compared on different questions. Checked on the stored values after the fact, so that no
// compiler rewrite of the rounding itself can hide a difference.
void check_same_rays(const Workload& workload) {
    std::size_t different = 0, total = 0;
    for (const RayBatch& batch : workload.batches)
        for (std::size_t i = 0; i < batch.rays.size(); ++i) {
            const Ray<double>& exact = batch.rays[i];
            const Ray<float>& rounded = batch.rays_float[i];
            ++total;
            if (Vec3<double>(rounded.origin) != exact.origin || Vec3<double>(rounded.direction) != exact.direction ||
                double(rounded.t_min) != exact.t_min || double(rounded.t_max) != exact.t_max)
                ++different;
        }
    if (different != 0)
        throw std::runtime_error(workload.name + ": " + std::to_string(different) + " of " + std::to_string(total) +
                                 " double rays are not exactly their float copies (the rounding was lost)");
}

// An orthonormal basis around a unit normal (Duff et al., "Building an Orthonormal Basis,
// Revisited", JCGT 2017).
void basis(const glm::dvec3& n, glm::dvec3& tangent, glm::dvec3& bitangent) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double b = n.x * n.y * a;
    tangent = {1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x};
    bitangent = {b, sign + n.y * n.y * a, -n.y};
}

// Camera rays through pixel centres at about primary_ray_target pixels; from each hit, a shadow
// ray to the light (where the light is in front of the surface, as a renderer traces it) and a
// cosine-distributed diffuse ray, both from the hit point offset along the normal facing the
// camera. The reference answers come from double-precision Watertight on the same rays.
void make_batches(Workload& workload) {
    const scene::Camera& camera = workload.scene.cameras.at(0);
    const glm::dvec3 light = workload.scene.point_lights.at(0).position;
    const double scale = std::sqrt(double(primary_ray_target) / (double(camera.width) * camera.height));
    const int width = std::max(1, int(std::lround(camera.width * scale)));
    const int height = std::max(1, int(std::lround(camera.height * scale)));
    const prism::PinholeCamera<double> pinhole(camera, width, height);

    const ReferenceGeometry& reference = geometry_of<double, prism::Bvh<prism::Watertight>>(workload);
    const auto bounds = reference.bounds();
    const double scene_radius = 0.5 * glm::length(bounds.max - bounds.min);

    RayBatch& primary = workload.batches[0];
    RayBatch& shadow = workload.batches[1];
    RayBatch& diffuse = workload.batches[2];
    shadow.any_hit = true;
    std::mt19937_64 random(795);
    const auto uniform = [&] { return double(random() >> 11) * 0x1p-53; };
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const Ray<double> ray = representable_in_float(pinhole.ray(x + 0.5, y + 0.5));
            primary.rays.push_back(ray);
            Ray<double> traced = ray;
            prism::Hit<double> hit;
            const bool found = prism::closest_hit(reference, traced, hit);
            primary.reference.push_back(found);
            if (!found) continue;
            const prism::SurfacePoint<double> point = reference.surface(traced, hit);
            glm::dvec3 normal = point.geometric_normal;
            if (glm::dot(normal, ray.direction) > 0) normal = -normal;
            const glm::dvec3 origin = point.position + origin_offset(point.position, scene_radius) * normal;

            const glm::dvec3 to_light = light - origin;
            const double light_distance = glm::length(to_light);
            if (glm::dot(to_light, normal) > 0)
                shadow.rays.push_back(representable_in_float({origin, to_light / light_distance, 0.0, light_distance}));

            glm::dvec3 tangent, bitangent;
            basis(normal, tangent, bitangent);
            const double u1 = uniform(), u2 = uniform();
            const double radius = std::sqrt(u1), phi = 2.0 * prism::pi<double> * u2;
            const glm::dvec3 direction = glm::normalize(radius * std::cos(phi) * tangent + radius * std::sin(phi) * bitangent +
                                                        std::sqrt(std::max(0.0, 1.0 - u1)) * normal);
            diffuse.rays.push_back(representable_in_float({origin, direction, 0.0, prism::infinity<double>}));
        }
    for (const Ray<double>& ray : shadow.rays) shadow.reference.push_back(prism::blocked(reference, ray));
    for (const Ray<double>& ray : diffuse.rays) {
        Ray<double> traced = ray;
        prism::Hit<double> hit;
        diffuse.reference.push_back(prism::closest_hit(reference, traced, hit));
    }
    for (RayBatch& batch : workload.batches)
        for (const Ray<double>& ray : batch.rays) batch.rays_float.push_back(to_float(ray));
    check_same_rays(workload);
}

// The scene's meshes only, for a comparison with Embree on exactly the same triangles.
scene::Scene meshes_only(scene::Scene scene) {
    scene.spheres.clear();
    scene.planes.clear();
    scene.mesh_instances.clear();
    return scene;
}

const fs::path course_scene_file =
    fs::path(PRISM_SHARED_DIR) / "ceng795/hw1/2022F_Batucan2601/System_Files/inputs/akif_uslu/ton_Roosendaal_smooth.xml";
const fs::path dragon_scene_file = fs::path(PRISM_SHARED_DIR) / "ceng795/hw1/2020_ozgurcanc/assets/scenes/dragon_lowres.xml";

Workload make_workload(const std::string& name, const std::function<scene::Scene()>& load) {
    Workload workload;
    workload.name = name;
    try {
        const auto start = std::chrono::steady_clock::now();
        workload.scene = load();
        if (workload.scene.cameras.empty() || workload.scene.point_lights.empty())
            throw std::runtime_error("the scene needs a camera and a point light");
        for (const auto& mesh : workload.scene.meshes) workload.triangle_count += mesh.triangles.size();
        make_batches(workload);
        std::fprintf(stderr, "workload %s: %zu triangles, %zu primary, %zu shadow, %zu diffuse rays (made in %.1f s)\n",
                     name.c_str(), workload.triangle_count, workload.batches[0].rays.size(),
                     workload.batches[1].rays.size(), workload.batches[2].rays.size(),
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    } catch (const std::exception& error) {
        workload.error = error.what();
    }
    return workload;
}

// The largest hw1 course scene: ton_Roosendaal_smooth, 78,620 triangles in three PLY meshes
// (the largest hw1 PLY, mesh_2.ply, holds 62,160), with the course's camera and light.
const Workload& course_workload() {
    static const Workload workload =
        make_workload("course", [] { return meshes_only(prism::io::load_scene(course_scene_file)); });
    return workload;
}

// The tiny-triangle dragon: dragon_lowres's dragon subdivided three times (11,971 -> 766,144
// triangles) at its original size, seen by the course file's camera, lit by its light.
const Workload& dragon_workload() {
    static const Workload workload = make_workload("dragon", [] {
        scene::Scene scene = meshes_only(prism::io::load_scene(dragon_scene_file));
        const std::size_t dragon = scene::subdivide_largest_mesh(scene, 3);
        scene::Mesh mesh = std::move(scene.meshes[dragon]);
        scene.meshes.clear();  // the mirror floor
        scene.meshes.push_back(std::move(mesh));
        return scene;
    });
    return workload;
}

using WorkloadGetter = const Workload& (*)();
constexpr std::array<std::pair<const char*, WorkloadGetter>, 2> workloads{
    {{"course", &course_workload}, {"dragon", &dragon_workload}}};

// ---------------------------------------------------------------------------------------------
// The variants: each answers a whole batch (hit, or occluded for shadow rays, per ray), tracing
// one ray at a time on the calling thread.

using Answers = std::vector<std::uint8_t>;
using TraceBatch = void (*)(const Workload&, const RayBatch&, Answers&);
using BuildBenchmark = void (*)(benchmark::State&, const Workload&);

template <class Real, class Policy>
void trace_prism(const Workload& workload, const RayBatch& batch, Answers& answers) {
    const auto& geometry = geometry_of<Real, Policy>(workload);
    const std::vector<Ray<Real>>& rays = batch.rays_in<Real>();
    if (batch.any_hit) {
        for (std::size_t i = 0; i < rays.size(); ++i) answers[i] = prism::blocked(geometry, rays[i]);
    } else {
        for (std::size_t i = 0; i < rays.size(); ++i) {
            Ray<Real> ray = rays[i];
            prism::Hit<Real> hit;
            answers[i] = prism::closest_hit(geometry, ray, hit);
        }
    }
}

template <class Real, class Policy>
void build_prism(benchmark::State& state, const Workload& workload) {
    for (auto _ : state) {
        const prism::SceneGeometry<Real, Policy> geometry(workload.scene);
        benchmark::DoNotOptimize(geometry.bounds());
    }
}

// Is it the tree or the kernel? prism's kernel (WideBvh<Watertight, 8>, float) on one mesh over
// every triangle of the workload, traced without SceneGeometry's top level, with the tree built
// by prism (prism_tree_float, WideBvhTree::build as the renderer builds it) or by Embree's
// generic SAH builder (embree_tree_*, below): the same kernel and code path, only the tree
// differs.
using TreeIndex = prism::WideBvhTree<float, 8>;
using BoxOf = std::function<prism::Aabb<float>(std::uint32_t)>;
using TreeBuilder = TreeIndex (*)(const Workload&, std::uint32_t count, const BoxOf& box_of);

// The tree `Build` makes, as the index of a policy: TriangleMesh builds it through Index::build
// like any index, so the mesh needs no hook for it. Build gets the workload being built (its
// triangles, for spatial splits) and keeps a copy of the tree for the statistics.
template <TreeBuilder Build>
struct BuiltIndex : TreeIndex {
    BuiltIndex() = default;
    explicit BuiltIndex(TreeIndex tree) : TreeIndex(std::move(tree)) {}
    template <class BoxOfTriangle>
    static BuiltIndex build(std::uint32_t count, const BoxOfTriangle& box_of) {
        last = Build(*building, count, BoxOf(box_of));
        return BuiltIndex(last);
    }
    static BuiltIndex build(std::span<const prism::Aabb<float>> boxes) {
        return build(std::uint32_t(boxes.size()), [boxes](std::uint32_t i) { return boxes[i]; });
    }
    static inline const Workload* building = nullptr;
    static inline TreeIndex last;
};

template <TreeBuilder Build>
struct BuiltWideBvh {
    using Intersector = prism::Watertight;
    static constexpr int packet_width = 8;
    template <prism::Scalar Real>
    using Index = BuiltIndex<Build>;
};

template <TreeBuilder Build>
using TreeMesh = prism::TriangleMesh<float, BuiltWideBvh<Build>>;

template <TreeBuilder Build>
struct BuiltTree {
    std::unique_ptr<TreeMesh<Build>> mesh;
    TreeIndex tree;  // a copy of the mesh's index, for the statistics
};

template <TreeBuilder Build>
BuiltTree<Build> build_tree_mesh(const Workload& workload) {
    std::vector<const scene::Mesh*> parts;
    for (const scene::Mesh& mesh : workload.scene.meshes) {
        // The mesh is traced in its object space: only right where that is the world's.
        if (mesh.transform != glm::dmat4(1.0)) throw std::runtime_error("tree variants need untransformed meshes");
        parts.push_back(&mesh);
    }
    BuiltIndex<Build>::building = &workload;
    BuiltTree<Build> built;
    built.mesh = std::make_unique<TreeMesh<Build>>(std::span<const scene::Mesh* const>(parts));
    built.tree = std::move(BuiltIndex<Build>::last);
    return built;
}

template <TreeBuilder Build>
const BuiltTree<Build>& tree_mesh_of(const Workload& workload) {
    static std::map<const Workload*, BuiltTree<Build>> cache;
    BuiltTree<Build>& built = cache[&workload];
    if (!built.mesh) built = build_tree_mesh<Build>(workload);
    return built;
}

template <TreeBuilder Build>
void trace_tree(const Workload& workload, const RayBatch& batch, Answers& answers) {
    const TreeMesh<Build>& mesh = *tree_mesh_of<Build>(workload).mesh;
    const std::vector<Ray<float>>& rays = batch.rays_float;
    if (batch.any_hit) {
        for (std::size_t i = 0; i < rays.size(); ++i) answers[i] = mesh.occluded(rays[i], rays[i].t_max);
    } else {
        for (std::size_t i = 0; i < rays.size(); ++i) {
            float t_max = rays[i].t_max;
            prism::Hit<float> hit;
            answers[i] = mesh.intersect(rays[i], t_max, hit, false);
        }
    }
}

template <TreeBuilder Build>
void build_tree(benchmark::State& state, const Workload& workload) {
    for (auto _ : state) {
        const BuiltTree<Build> built = build_tree_mesh<Build>(workload);
        benchmark::DoNotOptimize(built.mesh->bounds());
    }
}

TreeIndex prism_tree(const Workload&, std::uint32_t count, const BoxOf& box_of) { return TreeIndex::build(count, box_of); }

// prism's build with twice the SAH bins (32): whether a finer binned SAH makes a better tree.
TreeIndex prism_tree_bins32(const Workload&, std::uint32_t count, const BoxOf& box_of) {
    return TreeIndex::build(count, box_of, {.bin_count = 32, .max_leaf_size = 8});
}

// Embree 3: the same triangles (rounded to float as prism's float variants round them), one
// triangle geometry per mesh, default build quality; single rays (rtcIntersect1 / rtcOccluded1)
// like prism's, with RTC_SCENE_FLAG_ROBUST off or on.
#ifdef PRISM_BENCH_WITH_EMBREE

RTCDevice make_embree_device(const char* config) {
    RTCDevice made = rtcNewDevice(config);
    if (made == nullptr) throw std::runtime_error("rtcNewDevice failed");
    return made;
}

// One thread, as prism's builds are timed (the ray queries never use more).
RTCDevice embree_device() {
    static RTCDevice device = make_embree_device("threads=1");
    return device;
}

// Two threads, for the build's scaling (build_threads/). Made only when that benchmark runs:
// Embree caps TBB's parallelism for the whole process at the largest thread count of its live
// devices (a tbb::global_control it holds), so while only the one-thread device lives, no TBB
// work in this process, prism's included, runs on more than one thread.
RTCDevice embree_device_two_threads() {
    static RTCDevice device = make_embree_device("threads=2");
    return device;
}

RTCScene build_embree_scene(const scene::Scene& scene, bool robust, RTCDevice device = embree_device()) {
    RTCScene embree_scene = rtcNewScene(device);
    rtcSetSceneFlags(embree_scene, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    for (const scene::Mesh& mesh : scene.meshes) {
        // Placed in world space: Embree's scene is one BVH over every triangle, no instances.
        RTCGeometry geometry = prism::embree_triangle_geometry(device, mesh, mesh.transform);
        rtcAttachGeometry(embree_scene, geometry);
        rtcReleaseGeometry(geometry);
    }
    rtcCommitScene(embree_scene);
    return embree_scene;
}

RTCRay embree_ray(const Ray<float>& ray) {
    RTCRay result;
    result.org_x = ray.origin.x;
    result.org_y = ray.origin.y;
    result.org_z = ray.origin.z;
    result.tnear = ray.t_min;
    result.dir_x = ray.direction.x;
    result.dir_y = ray.direction.y;
    result.dir_z = ray.direction.z;
    result.time = 0.0f;
    result.tfar = ray.t_max;
    result.mask = ~0u;
    result.id = 0;
    result.flags = 0;
    return result;
}

template <bool Robust>
void trace_embree(const Workload& workload, const RayBatch& batch, Answers& answers) {
    static std::map<const Workload*, RTCScene> cache;
    RTCScene& embree_scene = cache[&workload];
    if (embree_scene == nullptr) embree_scene = build_embree_scene(workload.scene, Robust);
    const std::vector<Ray<float>>& rays = batch.rays_float;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    if (batch.any_hit) {
        for (std::size_t i = 0; i < rays.size(); ++i) {
            RTCRay ray = embree_ray(rays[i]);
            rtcOccluded1(embree_scene, &context, &ray);
            answers[i] = ray.tfar == -std::numeric_limits<float>::infinity();
        }
    } else {
        for (std::size_t i = 0; i < rays.size(); ++i) {
            RTCRayHit ray_hit;
            ray_hit.ray = embree_ray(rays[i]);
            ray_hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            ray_hit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(embree_scene, &context, &ray_hit);
            answers[i] = ray_hit.hit.geomID != RTC_INVALID_GEOMETRY_ID;
        }
    }
}

template <bool Robust>
void build_embree(benchmark::State& state, const Workload& workload) {
    for (auto _ : state) rtcReleaseScene(build_embree_scene(workload.scene, Robust));
}


// Embree's generic builder (rtcBuildBVH, Embree's own binned SAH, and with HIGH quality its
// spatial splits) laying out a prism WideBvhTree<float, 8>: Embree's nodes and leaves are
// created through callbacks into a tree of its thread-local memory, then copied into the layout
// WideBvhTree::build makes (nodes in pre-order, each leaf's range starting at a multiple of 8
// and padded with repeats of its last primitive).
struct EmbreeTreeSettings {
    RTCBuildQuality quality;
    unsigned max_leaf_size;   // at most 16, two of prism's packets, as prism's collapse allows
    unsigned sah_block_size;  // the SAH counts a leaf's primitives in blocks of this many
};

struct EmbreeBuiltNode {
    bool leaf;
    unsigned count;  // children, or primitives
};
struct EmbreeBuiltInner {
    EmbreeBuiltNode head;
    void* children[8];
    RTCBounds bounds[8];
};
struct EmbreeBuiltLeaf {
    EmbreeBuiltNode head;
    unsigned primitives[RTC_BUILD_MAX_PRIMITIVES_PER_LEAF];
};

// The triangles as the float kernel tests them (vertices rounded to float), numbered as the
// mesh numbers them (part after part), for the spatial splits' clipping.
struct EmbreeSplitContext {
    std::vector<std::array<glm::dvec3, 3>> triangles;
};

// The bounds of each side of a triangle's part inside `primitive`'s box, cut at `position` on
// axis `dimension`: the vertices on each side and the edges' crossings (in double, rounded
// outward to float), clipped to the primitive's box, as Embree's own triangle splitter does.
void split_triangle(const RTCBuildPrimitive* primitive, unsigned dimension, float position, RTCBounds* left, RTCBounds* right,
                    void* user) {
    const auto& triangle = static_cast<const EmbreeSplitContext*>(user)->triangles[primitive->primID];
    prism::Aabb<double> sides[2];
    for (int edge = 0; edge < 3; ++edge) {
        const glm::dvec3& a = triangle[edge];
        const glm::dvec3& b = triangle[(edge + 1) % 3];
        if (a[dimension] <= position) sides[0].extend(a);
        if (a[dimension] >= position) sides[1].extend(a);
        if ((a[dimension] < position && b[dimension] > position) || (a[dimension] > position && b[dimension] < position)) {
            glm::dvec3 crossing = a + (double(position) - a[dimension]) / (b[dimension] - a[dimension]) * (b - a);
            crossing[dimension] = position;
            sides[0].extend(crossing);
            sides[1].extend(crossing);
        }
    }
    const float lower[3] = {primitive->lower_x, primitive->lower_y, primitive->lower_z};
    const float upper[3] = {primitive->upper_x, primitive->upper_y, primitive->upper_z};
    RTCBounds* const out[2] = {left, right};
    for (int side = 0; side < 2; ++side) {
        float low[3], high[3];
        for (int axis = 0; axis < 3; ++axis) {
            low[axis] = std::max(lower[axis], prism::next_down(float(sides[side].min[axis])));
            high[axis] = std::min(upper[axis], prism::next_up(float(sides[side].max[axis])));
        }
        if (side == 0) high[dimension] = std::min(high[dimension], position);
        else low[dimension] = std::max(low[dimension], position);
        *out[side] = RTCBounds{low[0], low[1], low[2], 0.0f, high[0], high[1], high[2], 0.0f};
    }
}

struct WideLayout {
    std::vector<prism::WideBvhNode<float, 8>> nodes;
    std::vector<std::uint32_t> indices;

    std::uint32_t new_node() {
        nodes.push_back(prism::WideBvhNode<float, 8>::empty());
        return std::uint32_t(nodes.size() - 1);
    }

    void fill(std::uint32_t wide, int slot, const void* built, const RTCBounds& box) {
        const float low[3] = {box.lower_x, box.lower_y, box.lower_z}, high[3] = {box.upper_x, box.upper_y, box.upper_z};
        for (int axis = 0; axis < 3; ++axis) {
            nodes[wide].bounds[axis][slot] = low[axis];
            nodes[wide].bounds[3 + axis][slot] = high[axis];
        }
        const auto* head = static_cast<const EmbreeBuiltNode*>(built);
        if (head->leaf) {
            const auto* leaf = static_cast<const EmbreeBuiltLeaf*>(built);
            nodes[wide].set_leaf(slot, std::uint32_t(indices.size()), head->count);
            indices.insert(indices.end(), leaf->primitives, leaf->primitives + head->count);
            while (indices.size() % 8 != 0) indices.push_back(indices.back());
        } else {
            const std::uint32_t node = emit(static_cast<const EmbreeBuiltInner*>(built));
            nodes[wide].set_inner(slot, node);
        }
    }

    std::uint32_t emit(const EmbreeBuiltInner* inner) {
        const std::uint32_t wide = new_node();
        for (unsigned c = 0; c < inner->head.count; ++c) fill(wide, int(c), inner->children[c], inner->bounds[c]);
        return wide;
    }
};

template <const EmbreeTreeSettings& Settings>
TreeIndex embree_tree(const Workload& workload, std::uint32_t count, const BoxOf& box_of) {
    const bool spatial = Settings.quality == RTC_BUILD_QUALITY_HIGH;
    EmbreeSplitContext context;
    if (spatial)
        for (const scene::Mesh& mesh : workload.scene.meshes)
            for (const auto& face : mesh.triangles) {
                std::array<glm::dvec3, 3> triangle;
                for (int v = 0; v < 3; ++v) triangle[v] = glm::dvec3(glm::vec3(mesh.positions[face[v]]));
                context.triangles.push_back(triangle);
            }
    // Spatial splits add references: room for twice the triangles.
    std::vector<RTCBuildPrimitive> primitives(spatial ? 2 * std::size_t(count) : count);
    prism::Aabb<float> bounds;
    for (std::uint32_t i = 0; i < count; ++i) {
        const prism::Aabb<float> box = box_of(i);
        bounds.extend(box);
        primitives[i] = RTCBuildPrimitive{box.min.x, box.min.y, box.min.z, 0, box.max.x, box.max.y, box.max.z, i};
    }
    RTCBVH bvh = rtcNewBVH(embree_device());
    RTCBuildArguments arguments = rtcDefaultBuildArguments();
    arguments.buildQuality = Settings.quality;
    arguments.maxBranchingFactor = 8;
    arguments.maxDepth = 48;
    arguments.sahBlockSize = Settings.sah_block_size;
    arguments.minLeafSize = 1;
    arguments.maxLeafSize = Settings.max_leaf_size;
    arguments.traversalCost = 1.0f;
    arguments.intersectionCost = 1.0f;
    arguments.bvh = bvh;
    arguments.primitives = primitives.data();
    arguments.primitiveCount = count;
    arguments.primitiveArrayCapacity = primitives.size();
    arguments.createNode = [](RTCThreadLocalAllocator allocator, unsigned child_count, void*) -> void* {
        auto* inner = static_cast<EmbreeBuiltInner*>(rtcThreadLocalAlloc(allocator, sizeof(EmbreeBuiltInner), 16));
        inner->head = {false, child_count};
        return inner;
    };
    arguments.setNodeChildren = [](void* node, void** children, unsigned child_count, void*) {
        for (unsigned c = 0; c < child_count; ++c) static_cast<EmbreeBuiltInner*>(node)->children[c] = children[c];
    };
    arguments.setNodeBounds = [](void* node, const RTCBounds** child_bounds, unsigned child_count, void*) {
        for (unsigned c = 0; c < child_count; ++c) static_cast<EmbreeBuiltInner*>(node)->bounds[c] = *child_bounds[c];
    };
    arguments.createLeaf = [](RTCThreadLocalAllocator allocator, const RTCBuildPrimitive* leaf_primitives, size_t primitive_count,
                              void*) -> void* {
        auto* leaf = static_cast<EmbreeBuiltLeaf*>(rtcThreadLocalAlloc(allocator, sizeof(EmbreeBuiltLeaf), 16));
        leaf->head = {true, unsigned(primitive_count)};
        for (size_t i = 0; i < primitive_count; ++i) leaf->primitives[i] = leaf_primitives[i].primID;
        return leaf;
    };
    arguments.splitPrimitive = spatial ? &split_triangle : nullptr;
    arguments.userPtr = &context;
    void* root = rtcBuildBVH(&arguments);
    if (root == nullptr) throw std::runtime_error("rtcBuildBVH failed");
    WideLayout layout;
    if (static_cast<const EmbreeBuiltNode*>(root)->leaf) {
        // One leaf: a root with a single child, as WideBvhTree::build makes it.
        layout.fill(layout.new_node(), 0, root,
                    RTCBounds{bounds.min.x, bounds.min.y, bounds.min.z, 0.0f, bounds.max.x, bounds.max.y, bounds.max.z, 0.0f});
    } else {
        layout.emit(static_cast<const EmbreeBuiltInner*>(root));
    }
    rtcReleaseBVH(bvh);
    return TreeIndex::from_layout(std::move(layout.nodes), std::move(layout.indices), bounds);
}

// Embree's default-like settings for prism's 8-wide packets: leaves of up to two packets, the
// SAH counting packets (blocks of 8), as prism's collapse costs them; MEDIUM (binned SAH) and
// HIGH (binned SAH with spatial splits); and leaves of one packet at most.
constexpr EmbreeTreeSettings embree_medium{RTC_BUILD_QUALITY_MEDIUM, 16, 8};
constexpr EmbreeTreeSettings embree_high{RTC_BUILD_QUALITY_HIGH, 16, 8};
constexpr EmbreeTreeSettings embree_medium_leaf8{RTC_BUILD_QUALITY_MEDIUM, 8, 8};
#endif  // PRISM_BENCH_WITH_EMBREE

template <class Intersector>
using Bvh = prism::Bvh<Intersector>;
template <class Intersector, int Width>
using Wide = prism::WideBvh<Intersector, Width>;
template <prism::Precision P>
using DefaultAcceleration = typename prism::PrecisionPolicy<P>::Acceleration;

struct Variant {
    const char* name;
    bool robust;           // must agree with the double reference, else the benchmark stops
    TraceBatch trace;
    BuildBenchmark build;  // nullptr: it builds what another variant builds (naive = watertight)
};

const std::vector<Variant>& variants() {
    static const std::vector<Variant> list{
        {"naive_float", false, &trace_prism<float, Bvh<prism::NaiveEpsilon>>, nullptr},
        {"naive_double", false, &trace_prism<double, Bvh<prism::NaiveEpsilon>>, nullptr},
        {"watertight_float", true, &trace_prism<float, Bvh<prism::Watertight>>, &build_prism<float, Bvh<prism::Watertight>>},
        {"watertight_double", true, &trace_prism<double, Bvh<prism::Watertight>>,
         &build_prism<double, Bvh<prism::Watertight>>},
        {"double_refine_float", true, &trace_prism<float, Bvh<prism::DoubleRefine>>,
         &build_prism<float, Bvh<prism::DoubleRefine>>},
        {"wide4_float", true, &trace_prism<float, Wide<prism::Watertight, 4>>, &build_prism<float, Wide<prism::Watertight, 4>>},
        {"wide8_float", true, &trace_prism<float, Wide<prism::Watertight, 8>>, &build_prism<float, Wide<prism::Watertight, 8>>},
        {"wide4_double", true, &trace_prism<double, Wide<prism::Watertight, 4>>,
         &build_prism<double, Wide<prism::Watertight, 4>>},
        {"wide8_double", true, &trace_prism<double, Wide<prism::Watertight, 8>>,
         &build_prism<double, Wide<prism::Watertight, 8>>},
        {"wide4_double_refine", true, &trace_prism<float, Wide<prism::DoubleRefine, 4>>, nullptr},
        {"wide8_double_refine", true, &trace_prism<float, Wide<prism::DoubleRefine, 8>>, nullptr},
        // prism's kernel on one mesh, without SceneGeometry's top level: the tree experiment's base.
        {"prism_tree_float", true, &trace_tree<&prism_tree>, &build_tree<&prism_tree>},
        {"prism_tree_bins32_float", true, &trace_tree<&prism_tree_bins32>, &build_tree<&prism_tree_bins32>},
        // The renderer's own choices (render/render_scene.hpp), whatever they are today: the
        // ratio lines name them so their meaning survives a change of default.
        {"default_float", true, &trace_prism<float, DefaultAcceleration<prism::Precision::single>>, nullptr},
        {"default_double", true, &trace_prism<double, DefaultAcceleration<prism::Precision::double_all>>, nullptr},
        {"default_double_refine", true, &trace_prism<float, DefaultAcceleration<prism::Precision::double_refine>>,
         nullptr},
#ifdef PRISM_BENCH_WITH_EMBREE
        {"embree_tree_float", true, &trace_tree<&embree_tree<embree_medium>>, &build_tree<&embree_tree<embree_medium>>},
        {"embree_tree_high_float", true, &trace_tree<&embree_tree<embree_high>>, &build_tree<&embree_tree<embree_high>>},
        {"embree_tree_leaf8_float", true, &trace_tree<&embree_tree<embree_medium_leaf8>>,
         &build_tree<&embree_tree<embree_medium_leaf8>>},
        {"embree", false, &trace_embree<false>, &build_embree<false>},
        {"embree_robust", false, &trace_embree<true>, &build_embree<true>},
#endif
    };
    return list;
}

const Variant* find_variant(std::string_view name) {
    for (const Variant& variant : variants())
        if (name == variant.name) return &variant;
    return nullptr;
}

// ---------------------------------------------------------------------------------------------
// Checking answers

// A robust variant may disagree with the double reference only where the two precisions
// round differently on a ray that grazes a silhouette edge, or passes within rounding of a
// boundary edge of an open mesh (the dragon is open): a few rays per 100,000 at most (the
// rays are the same float-representable rays for every variant, so the ray itself is never
// the difference). 1e-4 of the batch (13 primary rays of 131,000) leaves room for that and
// still catches a real leak, which loses whole edges' worth of rays: thousands here.
constexpr double allowed_mismatch_fraction = 1e-4;

struct Agreement {
    std::size_t hits = 0, lost = 0, extra = 0;
    std::size_t mismatches() const { return lost + extra; }
};

Agreement compare(const Answers& answers, const Answers& reference) {
    Agreement agreement;
    for (std::size_t i = 0; i < answers.size(); ++i) {
        agreement.hits += answers[i];
        if (answers[i] && !reference[i]) ++agreement.extra;
        if (!answers[i] && reference[i]) ++agreement.lost;
    }
    return agreement;
}

// prism's watertight float answers, for Embree's ray-by-ray agreement with it.
const Answers& watertight_float_answers(const Workload& workload, BatchKind kind) {
    static std::map<std::pair<const Workload*, BatchKind>, Answers> cache;
    const auto [found, added] = cache.try_emplace({&workload, kind});
    if (added) {
        const RayBatch& batch = workload.batches[std::size_t(kind)];
        found->second.resize(batch.rays.size());
        trace_prism<float, Bvh<prism::Watertight>>(workload, batch, found->second);
    }
    return found->second;
}

// ---------------------------------------------------------------------------------------------
// The benchmarks

void trace_benchmark(benchmark::State& state, WorkloadGetter get, BatchKind kind, const Variant& variant) {
    const Workload& workload = get();
    if (!workload.error.empty()) return state.SkipWithError(workload.error.c_str());
    const RayBatch& batch = workload.batches[std::size_t(kind)];
    Answers answers(batch.rays.size());
    variant.trace(workload, batch, answers);  // untimed: builds the structure, warms the caches
    for (auto _ : state) {
        variant.trace(workload, batch, answers);
        benchmark::DoNotOptimize(answers.data());
        benchmark::ClobberMemory();
    }
    const Agreement agreement = compare(answers, batch.reference);
    const double rays = double(batch.rays.size());
    state.counters["rays_per_second"] = benchmark::Counter(rays * double(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["rays"] = rays;
    state.counters["hits"] = double(agreement.hits);
    state.counters["mismatches"] = double(agreement.mismatches());
    state.counters["lost"] = double(agreement.lost);
    state.counters["extra"] = double(agreement.extra);
    if (std::string_view(variant.name).starts_with("embree")) {
        const Answers& prism_answers = watertight_float_answers(workload, kind);
        std::size_t disagreements = 0;
        for (std::size_t i = 0; i < answers.size(); ++i) disagreements += answers[i] != prism_answers[i];
        state.counters["vs_watertight_float"] = double(disagreements);
    }
    if (variant.robust && double(agreement.mismatches()) > allowed_mismatch_fraction * rays) {
        std::ostringstream message;
        message << variant.name << " disagrees with the double-precision reference on " << agreement.mismatches()
                << " of " << batch.rays.size() << " rays (" << agreement.lost << " lost, " << agreement.extra
                << " extra; allowed: " << allowed_mismatch_fraction << " of the rays)";
        state.SkipWithError(message.str().c_str());
    }
}

// Builds run on one thread and are timed by the process's CPU time: the work of the build,
// which the load of a shared machine does not inflate the way it inflates wall-clock time.
void build_benchmark(benchmark::State& state, WorkloadGetter get, const Variant& variant) {
    const Workload& workload = get();
    if (!workload.error.empty()) return state.SkipWithError(workload.error.c_str());
    const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    variant.build(state, workload);
    state.counters["triangles"] = double(workload.triangle_count);
}

double wall_seconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double process_cpu_seconds() {
    timespec now;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
    return double(now.tv_sec) + 1e-9 * double(now.tv_nsec);
}

// Whether the parallel build scales: prism's default float structure and Embree's default
// build, each on one and on two threads, timed in interleaved rounds (a new random order each
// round) by the wall clock, which is what a second thread can lower, and by the process's CPU
// time, which says what the second thread costs in work. Ratios are taken within a round and
// their median over rounds reported. On a machine whose other jobs keep both cores busy a
// second thread has no core to run on, so the CPU columns (and `uptime`) must be read with it.
constexpr int scaling_rounds = 9;

void build_scaling_benchmark(benchmark::State& state, WorkloadGetter get) {
    const Workload& workload = get();
    if (!workload.error.empty()) return state.SkipWithError(workload.error.c_str());
    using DefaultFloat = DefaultAcceleration<prism::Precision::single>;
    struct Contender {
        const char* name;
        int threads;
        std::function<void()> build;
        std::vector<double> wall, cpu;
    };
    std::vector<Contender> contenders;
    for (const int threads : {1, 2})
        contenders.push_back({"prism", threads, [&workload] {
                                  const prism::SceneGeometry<float, DefaultFloat> geometry(workload.scene);
                                  benchmark::DoNotOptimize(geometry.bounds());
                              }, {}, {}});
#ifdef PRISM_BENCH_WITH_EMBREE
    contenders.push_back({"embree", 1, [&workload] { rtcReleaseScene(build_embree_scene(workload.scene, false)); }, {}, {}});
    contenders.push_back({"embree", 2, [&workload] {
                              rtcReleaseScene(build_embree_scene(workload.scene, false, embree_device_two_threads()));
                          }, {}, {}});
#endif
    std::vector<std::size_t> order(contenders.size());
    std::iota(order.begin(), order.end(), std::size_t(0));
    std::mt19937 random(2026);
    for (Contender& contender : contenders) {  // untimed: the devices, the allocator's first pages
        const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, std::size_t(contender.threads));
        contender.build();
    }
    for (auto _ : state) {
        for (int round = 0; round < scaling_rounds; ++round) {
            std::shuffle(order.begin(), order.end(), random);
            for (const std::size_t c : order) {
                Contender& contender = contenders[c];
                const tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                                  std::size_t(contender.threads));
                const double wall = wall_seconds(), cpu = process_cpu_seconds();
                contender.build();
                contender.cpu.push_back(process_cpu_seconds() - cpu);
                contender.wall.push_back(wall_seconds() - wall);
            }
        }
    }
    const auto median = [](std::vector<double> values) {
        std::sort(values.begin(), values.end());
        return values[values.size() / 2];
    };
    const auto ratio = [&](const Contender& a, const Contender& b, bool wall) {
        std::vector<double> ratios;
        for (std::size_t round = 0; round < a.wall.size(); ++round)
            ratios.push_back(wall ? a.wall[round] / b.wall[round] : a.cpu[round] / b.cpu[round]);
        return median(ratios);
    };
    for (const Contender& contender : contenders) {
        const std::string name = std::string(contender.name) + "_" + std::to_string(contender.threads) + "t";
        state.counters[name + "_wall_ms"] = 1e3 * median(contender.wall);
        state.counters[name + "_cpu_ms"] = 1e3 * median(contender.cpu);
    }
    // Two threads over one, and prism over Embree at each thread count, by wall clock.
    state.counters["prism_2t/1t"] = ratio(contenders[1], contenders[0], true);
    if (contenders.size() == 4) {
        state.counters["embree_2t/1t"] = ratio(contenders[3], contenders[2], true);
        state.counters["prism/embree_1t"] = ratio(contenders[0], contenders[2], true);
        state.counters["prism/embree_2t"] = ratio(contenders[1], contenders[3], true);
        state.counters["prism/embree_1t_cpu"] = ratio(contenders[0], contenders[2], false);
    }
    state.counters["triangles"] = double(workload.triangle_count);
}

// The ratios, measured in pairs: on a shared machine the load drifts between one benchmark
// and the next, so separate benchmarks' medians compare different machines. Here every round
// traces the batch once with each variant, in a new random order, timed by the thread's CPU
// clock; a ratio is taken within each round and the median over rounds is reported, with
// its quartiles to show the noise.
constexpr int paired_rounds = 21;
constexpr std::array<std::pair<const char*, const char*>, 23> ratio_pairs{{
    {"default_float", "embree"},
    {"default_float", "embree_robust"},
    {"default_double", "default_float"},
    {"default_double_refine", "default_float"},
    {"default_float", "watertight_float"},
    {"wide4_float", "watertight_float"},
    {"wide8_float", "wide4_float"},
    {"wide4_double", "wide4_float"},
    {"wide8_double", "wide4_double"},
    {"wide4_double_refine", "wide4_float"},
    {"wide8_double_refine", "wide4_double_refine"},
    {"wide4_float", "embree"},
    {"watertight_float", "naive_float"},
    {"double_refine_float", "watertight_float"},
    {"watertight_double", "watertight_float"},
    {"watertight_float", "embree"},
    {"watertight_float", "embree_robust"},
    // The tree experiment: the same kernel on Embree's trees and on prism's.
    {"prism_tree_float", "default_float"},
    {"embree_tree_float", "prism_tree_float"},
    {"embree_tree_high_float", "prism_tree_float"},
    {"embree_tree_leaf8_float", "prism_tree_float"},
    {"prism_tree_bins32_float", "prism_tree_float"},
    {"prism_tree_float", "embree"},
}};

double thread_cpu_seconds() {
    timespec now;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
    return double(now.tv_sec) + 1e-9 * double(now.tv_nsec);
}

void paired_ratio_benchmark(benchmark::State& state, WorkloadGetter get, BatchKind kind) {
    const Workload& workload = get();
    if (!workload.error.empty()) return state.SkipWithError(workload.error.c_str());
    const RayBatch& batch = workload.batches[std::size_t(kind)];
    const std::vector<Variant>& list = variants();
    Answers answers(batch.rays.size());
    for (const Variant& variant : list) variant.trace(workload, batch, answers);  // untimed: build and warm up
    std::vector<std::vector<double>> seconds(list.size());
    std::vector<std::size_t> order(list.size());
    std::iota(order.begin(), order.end(), std::size_t(0));
    std::mt19937 random(2025);
    for (auto _ : state) {
        for (int round = 0; round < paired_rounds; ++round) {
            std::shuffle(order.begin(), order.end(), random);
            for (const std::size_t v : order) {
                const double start = thread_cpu_seconds();
                list[v].trace(workload, batch, answers);
                seconds[v].push_back(thread_cpu_seconds() - start);
            }
        }
    }
    for (const auto& [first, second] : ratio_pairs) {
        const Variant *a = find_variant(first), *b = find_variant(second);
        if (a == nullptr || b == nullptr) continue;
        const std::vector<double>&seconds_a = seconds[std::size_t(a - list.data())],
              &seconds_b = seconds[std::size_t(b - list.data())];
        std::vector<double> ratios;
        for (std::size_t round = 0; round < seconds_a.size(); ++round) ratios.push_back(seconds_a[round] / seconds_b[round]);
        std::sort(ratios.begin(), ratios.end());
        const std::string name = std::string(first) + "/" + second;
        state.counters[name] = ratios[ratios.size() / 2];
        state.counters[name + "_p25"] = ratios[ratios.size() / 4];
        state.counters[name + "_p75"] = ratios[ratios.size() * 3 / 4];
    }
    state.counters["rays"] = double(batch.rays.size());
}

// ---------------------------------------------------------------------------------------------
// The summary after the run: the paired ratios, each variant's rays per second (median over
// repetitions) and answers, the build times.

class SummaryReporter : public benchmark::ConsoleReporter {
public:
    void ReportRuns(const std::vector<Run>& runs) override {
        for (const Run& run : runs) {
            if (run.error_occurred) continue;
            const bool median_aggregate = run.run_type == Run::RT_Aggregate && run.aggregate_name == "median";
            if (run.run_type == Run::RT_Aggregate && !median_aggregate) continue;
            Record& record = records_[run.run_name.function_name];
            const double seconds = run.GetAdjustedCPUTime() / benchmark::GetTimeUnitMultiplier(run.time_unit);
            const auto rate = run.counters.find("rays_per_second");
            if (median_aggregate) {
                record.median_seconds = seconds;
                if (rate != run.counters.end()) record.median_rate = rate->second.value;
            } else {
                record.seconds.push_back(seconds);
                if (rate != run.counters.end()) record.rates.push_back(rate->second.value);
            }
            for (const auto& [name, counter] : run.counters) record.counters[name] = counter.value;
        }
        ConsoleReporter::ReportRuns(runs);
    }

    void Finalize() override {
        ConsoleReporter::Finalize();
        std::ostream& out = GetOutputStream();
        out << std::fixed;
        out << "\nSummary of this run\n";
        for (const auto& [workload, getter] : workloads) {
            (void)getter;
            for (BatchKind kind : batch_kinds) {
                const std::string path = std::string(workload) + "/" + batch_name(kind);
                out << path << ":\n";
                if (const auto found = records_.find("ratios/" + path); found != records_.end()) {
                    const auto& counters = found->second.counters;
                    out << "  time ratios, paired (median of " << paired_rounds << " rounds [quartiles]):\n";
                    for (const auto& [first, second] : ratio_pairs) {
                        const std::string name = std::string(first) + "/" + second;
                        if (!counters.count(name)) continue;
                        out << "    " << std::left << std::setw(46) << (std::string(first) + " / " + second) << std::right
                            << std::setprecision(3) << counters.at(name) << "  [" << counters.at(name + "_p25") << ", "
                            << counters.at(name + "_p75") << "]\n";
                    }
                }
                out << "  variant                  Mrays/s        hits  mismatches (lost, extra) of rays\n";
                for (const Variant& variant : variants()) {
                    const auto found = records_.find("rays/" + path + "/" + variant.name);
                    if (found == records_.end()) continue;
                    const Record& record = found->second;
                    const auto counter = [&](const char* key) {
                        const auto value = record.counters.find(key);
                        return value == record.counters.end() ? std::string("-") : std::to_string(std::llround(value->second));
                    };
                    out << "    " << std::left << std::setw(24) << variant.name << std::right << std::setw(10)
                        << std::setprecision(2) << record.rate().value_or(0) * 1e-6 << std::setw(12) << counter("hits")
                        << std::setw(12) << counter("mismatches") << " (" << counter("lost") << ", " << counter("extra")
                        << ") of " << counter("rays");
                    if (record.counters.count("vs_watertight_float"))
                        out << "; differs from watertight_float on " << counter("vs_watertight_float");
                    out << "\n";
                }
            }
        }
        out << "build times (median CPU time, one thread):\n";
        for (const auto& [name, record] : records_) {
            if (!name.starts_with("build/")) continue;
            out << "  " << std::left << std::setw(36) << name << std::right << std::setprecision(1)
                << record.time().value_or(0) * 1e3 << " ms\n";
        }
    }

private:
    static std::optional<double> median(std::vector<double> values) {
        if (values.empty()) return std::nullopt;
        std::sort(values.begin(), values.end());
        const std::size_t n = values.size();
        return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
    }

    struct Record {
        std::vector<double> seconds, rates;  // per repetition
        std::optional<double> median_seconds, median_rate;  // the median aggregate, if reported
        std::map<std::string, double> counters;
        std::optional<double> rate() const { return median_rate ? median_rate : median(rates); }
        std::optional<double> time() const { return median_seconds ? median_seconds : median(seconds); }
    };

    std::map<std::string, Record> records_;
};

void register_benchmarks() {
    for (const auto& [workload, getter] : workloads) {
        for (BatchKind kind : batch_kinds) {
            const std::string path = std::string(workload) + "/" + batch_name(kind);
            for (const Variant& variant : variants())
                benchmark::RegisterBenchmark(("rays/" + path + "/" + variant.name).c_str(),
                                             [&variant, getter = getter, kind](benchmark::State& state) {
                                                 trace_benchmark(state, getter, kind, variant);
                                             })
                    ->Unit(benchmark::kMillisecond);
            benchmark::RegisterBenchmark(("ratios/" + path).c_str(),
                                         [getter = getter, kind](benchmark::State& state) {
                                             paired_ratio_benchmark(state, getter, kind);
                                         })
                ->Iterations(1)
                ->Repetitions(1)
                ->Unit(benchmark::kSecond);
        }
        for (const Variant& variant : variants()) {
            if (variant.build == nullptr) continue;
            benchmark::RegisterBenchmark(
                (std::string("build/") + workload + "/" + variant.name).c_str(),
                [&variant, getter = getter](benchmark::State& state) { build_benchmark(state, getter, variant); })
                ->Unit(benchmark::kMillisecond)
                ->MeasureProcessCPUTime();
        }
        benchmark::RegisterBenchmark((std::string("build_threads/") + workload).c_str(),
                                     [getter = getter](benchmark::State& state) { build_scaling_benchmark(state, getter); })
            ->Iterations(1)
            ->Repetitions(1)
            ->Unit(benchmark::kSecond);
    }
}


// ---------------------------------------------------------------------------------------------
// The counting build (prism_tree_stats, PRISM_TRAVERSAL_STATS): each tree's shape and what the
// kernel does per ray on it, for every batch of both workloads.
#ifdef PRISM_TRAVERSAL_STATS

struct TreeShape {
    std::size_t inner = 0, leaves = 0, children = 0, slots = 0;
    std::array<std::size_t, 33> leaf_sizes{};  // the last counts 32 and more
    // The surface area heuristic as prism's collapse costs a tree: a node test and a packet
    // test cost 1 each, times the box's area relative to the root's.
    double sah = 0;
    // The same with leaves costed per triangle (Embree's intersection cost per primitive), and
    // per block of 4 (Embree's verbose statistics of its BVH8<triangle4>, for comparison).
    double sah_triangles = 0, sah_nodes = 0, sah_blocks4 = 0;
};

void measure_shape(const TreeIndex& tree, std::uint32_t node, double area, double root_area, TreeShape& shape) {
    const auto& wide = tree.nodes()[node];
    ++shape.inner;
    shape.sah += area / root_area;
    shape.sah_triangles += area / root_area;
    shape.sah_nodes += area / root_area;
    for (int slot = 0; slot < 8; ++slot) {
        prism::Aabb<float> box;
        for (int axis = 0; axis < 3; ++axis) {
            box.min[axis] = wide.bounds[axis][slot];
            box.max[axis] = wide.bounds[3 + axis][slot];
        }
        if (box.min.x > box.max.x) continue;  // an empty slot
        ++shape.children;
        const double child_area = double(box.half_area());
        if (wide.count(slot) == 0) {
            measure_shape(tree, wide.index(slot), child_area, root_area, shape);
        } else {
            ++shape.leaves;
            const std::uint32_t count = wide.count(slot);
            ++shape.leaf_sizes[std::min<std::size_t>(count, shape.leaf_sizes.size() - 1)];
            shape.slots += (count + 7) / 8 * 8;
            shape.sah += child_area / root_area * double((count + 7) / 8);
            shape.sah_triangles += child_area / root_area * double(count);
            shape.sah_blocks4 += child_area / root_area * double((count + 3) / 4);
        }
    }
}

template <TreeBuilder Build>
void print_tree_statistics(const char* name, const Workload& workload) {
    const auto& built = tree_mesh_of<Build>(workload);
    TreeShape shape;
    measure_shape(built.tree, 0, double(built.tree.bounds().half_area()), double(built.tree.bounds().half_area()), shape);
    std::printf("%s %s: %zu nodes (%.2f children each), %zu leaves (%.2f triangles each), %zu slots for %zu triangles, "
                "SAH %.2f (per packet) %.2f (per triangle), %.1f bytes per triangle (nodes, indices, packets)\n"
                "  SAH of the nodes %.3f, of the leaves per packet %.3f, per block of 4 %.3f\n",
                workload.name.c_str(), name, shape.inner, double(shape.children) / double(shape.inner), shape.leaves,
                double(workload.triangle_count) / double(shape.leaves), shape.slots, workload.triangle_count, shape.sah,
                shape.sah_triangles, double(built.mesh->accelerator_bytes()) / double(workload.triangle_count), shape.sah_nodes,
                shape.sah - shape.sah_nodes, shape.sah_blocks4);
    std::printf("  leaf sizes:");
    for (std::size_t size = 1; size < shape.leaf_sizes.size(); ++size)
        if (shape.leaf_sizes[size] != 0) std::printf(" %zu:%zu", size, shape.leaf_sizes[size]);
    std::printf("\n  per ray       nodes  boxes entered  leaves  packets  triangles\n");
    for (BatchKind kind : batch_kinds) {
        const RayBatch& batch = workload.batches[std::size_t(kind)];
        Answers answers(batch.rays.size());
        prism::traversal_stats = {};
        trace_tree<Build>(workload, batch, answers);
        const prism::TraversalStats counts = prism::traversal_stats;
        const double rays = double(batch.rays.size());
        std::printf("  %-10s %8.2f %14.2f %7.2f %8.2f %10.2f\n", batch_name(kind), double(counts.nodes) / rays,
                    double(counts.boxes_entered) / rays, double(counts.leaves) / rays, double(counts.packets) / rays,
                    double(counts.triangles) / rays);
    }
}

int print_traversal_statistics() {
    for (const auto& [name, getter] : workloads) {
        const Workload& workload = getter();
        if (!workload.error.empty()) continue;
        print_tree_statistics<&prism_tree>("prism_tree", workload);
        print_tree_statistics<&prism_tree_bins32>("prism_tree_bins32", workload);
#ifdef PRISM_BENCH_WITH_EMBREE
        print_tree_statistics<&embree_tree<embree_medium>>("embree_tree", workload);
        print_tree_statistics<&embree_tree<embree_high>>("embree_tree_high", workload);
        print_tree_statistics<&embree_tree<embree_medium_leaf8>>("embree_tree_leaf8", workload);
        // Embree's own tree for its own kernel, as its verbose mode reports it.
        std::fflush(stdout);
        RTCDevice verbose = make_embree_device("threads=1,verbose=2");
        rtcReleaseScene(build_embree_scene(workload.scene, false, verbose));
        rtcReleaseDevice(verbose);
        std::fflush(stdout);
#endif
    }
    return 0;
}

#endif  // PRISM_TRAVERSAL_STATS

}  // namespace

int main(int argc, char** argv) {
#ifdef PRISM_TRAVERSAL_STATS
    (void)argc;
    (void)argv;
    return print_traversal_statistics();
#endif
    register_benchmarks();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    SummaryReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();
    return 0;
}
