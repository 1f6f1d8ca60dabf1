// Embree 3 as an acceleration policy: `Config<float, Embree, ...>` renders any scene with Embree
// finding the hits and prism doing everything else. Embree replaces prism's index (SceneIndex),
// not the surfaces: EmbreeGeometry is prism's SceneSurfaces (built once, meshes in the file's
// triangle order, the order Embree names them in) with Embree's scene beside it, which mirrors
// the objects, Embree's geometry IDs equal to prism's object numbers (place_objects). Embree says which triangle of which object is hit first; prism's own test on that
// one triangle then computes t and the barycentrics, so a hit is shaded from exactly the
// numbers prism's own accelerator would give for it; where prism's test declines (an edge
// Embree's float test takes and the watertight test gives to the neighbour) Embree's own
// numbers stand. Rejecting such candidates in a filter instead, so that prism decides every
// one, made it worse in float (hw1 bunny 102.3 -> 78.2 dB): Embree's test then never offers the
// neighbour the watertight test would have taken, and the ray leaks through the edge.
// Needs libembree-dev; the CMake build defines PRISM_WITH_EMBREE when it finds it.
#pragma once

#include <prism/accel/accelerator.hpp>
#include <prism/geometry/planes.hpp>
#include <prism/geometry/ray_batch.hpp>
#include <prism/geometry/scene_surfaces.hpp>
#include <prism/geometry/triangle_mesh.hpp>

#include <embree3/rtcore.h>
#include <glm/gtc/matrix_transform.hpp>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace prism {

template <Scalar Real, bool MotionBlur> class EmbreeGeometry;

// A mesh as a committed Embree triangle geometry of `device`, its vertices placed by `to_world`
// (computed in double) and rounded once to float, as prism's float meshes round them. The one
// place prism fills Embree's buffers: EmbreeGeometry and bench/intersect_bench.cpp use it.
inline RTCGeometry embree_triangle_geometry(RTCDevice device, const scene::Mesh& mesh,
                                            const glm::dmat4& to_world = glm::dmat4(1.0)) {
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.positions.size()));
    const bool placed = to_world != glm::dmat4(1.0);
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        const glm::vec3 p(placed ? glm::dvec3(to_world * glm::dvec4(mesh.positions[v], 1.0)) : mesh.positions[v]);
        vertices[3 * v + 0] = p.x;
        vertices[3 * v + 1] = p.y;
        vertices[3 * v + 2] = p.z;
    }
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh.triangles.size()));
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k) indices[3 * t + k] = mesh.triangles[t][k];
    rtcCommitGeometry(geometry);
    return geometry;
}

// The policy. Intersector and Index name how the shapes are stored for prism's own per-primitive
// test (AccelerationPolicy); Geometry is what the renderer builds instead of SceneGeometry.
struct Embree {
    using Intersector = Watertight;
    template <Scalar Real> using Index = PrimitiveList<Real>;
    template <Scalar Real, bool MotionBlur> using Geometry = EmbreeGeometry<Real, MotionBlur>;
};

// Embree's traversal and triangle test are in float. In a double renderer that is not enough:
// rays leave surfaces by double-precision error bounds, far below a float ulp, and Embree's
// float test alone finds the surface a ray just left (4% of the shadow rays of hw2
// horse_instanced came back occluded). So in double every triangle Embree's test accepts is
// tested again by prism's double test in a filter callback, and only prism's yes counts.
template <Scalar Real, bool MotionBlur = false>
class EmbreeGeometry : public SceneSurfaces<Real, Watertight, MotionBlur> {
public:
    using Surfaces = SceneSurfaces<Real, Watertight, MotionBlur>;

    explicit EmbreeGeometry(const scene::Scene& scene, unsigned threads = 0)
        : Surfaces(scene,
                   place_objects<Real>(
                       scene, [&](std::size_t m) { return TriangleMesh<Real, BruteForce<Watertight>>::bounds_of(scene.meshes[m]); },
                       MotionBlur),
                   [](std::size_t) { return std::span<const std::uint32_t>(); }),
          planes_(scene, std::uint32_t(scene.meshes.size() + scene.mesh_instances.size() + scene.spheres.size())),
          device_(make_device(threads)), scene_(rtcNewScene(device_.get())) {
        std::vector<std::uint32_t> object_of_mesh(scene.meshes.size());
        std::uint32_t object = 0;
        for (std::size_t m = 0; m < scene.meshes.size(); ++m)
            add_mesh_object(scene, m, scene.meshes[m].transform, scene.meshes[m].motion, object++);
        for (const auto& instance : scene.mesh_instances)
            add_mesh_object(scene, instance.base_mesh, instance.transform, instance.motion, object++);
        user_data_.reserve(scene.spheres.size());
        for (std::size_t s = 0; s < scene.spheres.size(); ++s) add_sphere_object(object++);
        if (object != this->instance_count())
            throw std::logic_error("EmbreeGeometry: objects out of step with the surfaces");
        rtcSetSceneFlags(scene_.get(), RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
        rtcCommitScene(scene_.get());
        check("committing the scene");
    }

    // The query seam's two entries (geometry/ray_batch.hpp), each active ray queried on its own:
    // Embree's single-ray queries, with prism's own test on the primitive Embree finds.
    std::uint32_t intersect(const RayBatch<Real>& batch, Hit<Real>* hits) const {
        std::uint32_t found = 0;
        for (std::uint32_t lanes = batch.active; lanes != 0; lanes &= lanes - 1) {
            const int i = std::countr_zero(lanes);
            // Triangles cull under both rules that cull; planes only under `all` (as SceneIndex).
            const bool hit = closest_one(batch.rays[i], hits[i], culls_back_faces(batch.culling));
            if (planes_.closest(batch.rays[i], hits[i], culls_planes(batch.culling)) || hit)
                found |= std::uint32_t(1) << i;
        }
        return found;
    }
    std::uint32_t occluded(const RayBatch<Real>& batch) const {
        std::uint32_t blocked = 0;
        for (std::uint32_t lanes = batch.active; lanes != 0; lanes &= lanes - 1) {
            const int i = std::countr_zero(lanes);
            if (occluded_one(batch.rays[i])) blocked |= std::uint32_t(1) << i;
        }
        return blocked;
    }

    // Bytes Embree holds for this scene (its BVHs and copies of the triangles), as its memory
    // monitor counted them during the build.
    std::int64_t embree_bytes() const { return device_.bytes(); }

private:
    // Closest hit in (ray.t_min, ray.t_max] among every surface but the planes; on a hit,
    // ray.t_max becomes the hit distance. `cull`: back-facing triangles are skipped (the
    // filter that culls, chosen here at run time as prism's own index takes the flag).
    bool closest_one(Ray<Real>& ray, Hit<Real>& hit, bool cull) const {
        RTCRayHit ray_hit;
        ray_hit.ray = embree_ray(ray, ray.t_max);
        ray_hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        ray_hit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        Context context(this, ray);
        context.base.filter = cull ? filter_for<true, false>() : filter_for<false, false>();
        rtcIntersect1(scene_.get(), &context.base, &ray_hit);
        bool found = false;
        if (ray_hit.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
            const std::uint32_t object =
                ray_hit.hit.instID[0] != RTC_INVALID_GEOMETRY_ID ? ray_hit.hit.instID[0] : ray_hit.hit.geomID;
            // prism's test on Embree's primitive (in double the filter already accepted it).
            Ray<Real> probe = ray;
            if (!this->intersect_primitive(object, ray_hit.hit.primID, probe, hit))
                hit = Hit<Real>{Real(ray_hit.ray.tfar), object, ray_hit.hit.primID, Real(ray_hit.hit.u),
                                Real(ray_hit.hit.v)};
            ray.t_max = hit.t;
            found = true;
        }
        return found;
    }

    // Whether anything lies in (ray.t_min, ray.t_max): open at t_max, like prism's own.
    bool occluded_one(const Ray<Real>& ray) const {
        RTCRay embree = embree_ray(ray, ray.t_max);
        // Open at t_max: in float Embree's closed interval is shortened by an ulp; in double
        // prism's test in the filter decides, so Embree's interval must not end early.
        if (embree.tfar < std::numeric_limits<float>::infinity())
            embree.tfar = std::nextafter(embree.tfar, exact_filter ? std::numeric_limits<float>::infinity()
                                                                   : -std::numeric_limits<float>::infinity());
        Context context(this, ray);
        context.base.filter = filter_for<false, true>();
        rtcOccluded1(scene_.get(), &context.base, &embree);
        return embree.tfar == -std::numeric_limits<float>::infinity() || planes_.occludes(ray);
    }

    // Embree's handles, released in order (scene before device).
    struct DeviceHandle {
        RTCDevice device = nullptr;
        std::unique_ptr<std::int64_t> bytes_in_use = std::make_unique<std::int64_t>(0);
        RTCDevice get() const { return device; }
        std::int64_t bytes() const { return *bytes_in_use; }
        DeviceHandle(RTCDevice d) : device(d) {}
        DeviceHandle(DeviceHandle&& other) noexcept
            : device(std::exchange(other.device, nullptr)), bytes_in_use(std::move(other.bytes_in_use)) {}
        ~DeviceHandle() {
            if (device) rtcReleaseDevice(device);
        }
    };
    struct SceneHandle {
        RTCScene scene = nullptr;
        RTCScene get() const { return scene; }
        explicit SceneHandle(RTCScene s) : scene(s) {}
        SceneHandle(SceneHandle&& other) noexcept : scene(std::exchange(other.scene, nullptr)) {}
        ~SceneHandle() {
            if (scene) rtcReleaseScene(scene);
        }
    };

    // The intersect context carries the geometry to the callbacks (Embree's documented way of
    // passing per-query data: a struct that starts with RTCIntersectContext).
    struct Context {
        RTCIntersectContext base;
        const EmbreeGeometry* self;
        const Ray<Real>* world_ray;  // the query's ray, in Real, for prism's test in the filter
        Context(const EmbreeGeometry* geometry, const Ray<Real>& ray) : self(geometry), world_ray(&ray) {
            rtcInitIntersectContext(&base);
        }
    };

    struct SphereUserData {
        const EmbreeGeometry* self;
        std::uint32_t object;
    };

    DeviceHandle make_device(unsigned threads) {
        const std::string config = threads > 0 ? "threads=" + std::to_string(threads) : std::string();
        RTCDevice device = rtcNewDevice(config.empty() ? nullptr : config.c_str());
        if (device == nullptr) throw std::runtime_error("Embree: rtcNewDevice failed");
        DeviceHandle handle(device);
        rtcSetDeviceMemoryMonitorFunction(
            device,
            [](void* user, ssize_t bytes, bool) {
                *static_cast<std::int64_t*>(user) += bytes;
                return true;
            },
            handle.bytes_in_use.get());
        return handle;
    }

    void check(const char* what) const {
        const RTCError error = rtcGetDeviceError(device_.get());
        if (error != RTC_ERROR_NONE)
            throw std::runtime_error(std::string("Embree: error ") + std::to_string(int(error)) + " " + what);
    }

    static RTCRay embree_ray(const Ray<Real>& ray, Real t_max) {
        RTCRay result;
        result.org_x = float(ray.origin.x);
        result.org_y = float(ray.origin.y);
        result.org_z = float(ray.origin.z);
        result.tnear = float(ray.t_min);
        result.dir_x = float(ray.direction.x);
        result.dir_y = float(ray.direction.y);
        result.dir_z = float(ray.direction.z);
        result.time = float(ray.time);
        result.tfar = float(t_max);
        result.mask = ~0u;
        result.id = 0;
        result.flags = 0;
        return result;
    }

    // The mesh's triangles in its object space, as a float triangle geometry; one Embree scene
    // per mesh, made once and shared by every object that places it.
    RTCScene mesh_scene(const scene::Scene& scene, std::size_t mesh_index) {
        if (mesh_scenes_.size() < scene.meshes.size()) mesh_scenes_.resize(scene.meshes.size());
        std::unique_ptr<SceneHandle>& cached = mesh_scenes_[mesh_index];
        if (cached) return cached->get();
        cached = std::make_unique<SceneHandle>(rtcNewScene(device_.get()));
        RTCGeometry geometry = embree_triangle_geometry(device_.get(), scene.meshes[mesh_index]);
        rtcAttachGeometryByID(cached->get(), geometry, 0);
        rtcReleaseGeometry(geometry);
        rtcSetSceneFlags(cached->get(), RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
        rtcCommitScene(cached->get());
        check("building a mesh");
        return cached->get();
    }


    // A mesh placed by `transform` (and moving by `motion` over the shutter): its triangles go
    // straight into the top scene when it is not moved at all, else an instance of its scene.
    void add_mesh_object(const scene::Scene& scene, std::size_t mesh_index, const glm::dmat4& transform,
                         const glm::dvec3& motion, std::uint32_t object) {
        const bool moving = MotionBlur && motion != glm::dvec3(0.0);
        RTCGeometry geometry;
        if (transform == glm::dmat4(1.0) && !moving) {
            geometry = embree_triangle_geometry(device_.get(), scene.meshes[mesh_index]);
        } else {
            geometry = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(geometry, mesh_scene(scene, mesh_index));
            rtcSetGeometryTimeStepCount(geometry, moving ? 2 : 1);
            const glm::mat4 at_start(transform);
            rtcSetGeometryTransform(geometry, 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, &at_start[0][0]);
            if (moving) {
                // A translation is linear in time, so Embree's interpolation of the two ends is
                // the motion itself.
                const glm::mat4 at_end(glm::translate(glm::dmat4(1.0), motion) * transform);
                rtcSetGeometryTransform(geometry, 1, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, &at_end[0][0]);
            }
            rtcCommitGeometry(geometry);
        }
        rtcAttachGeometryByID(scene_.get(), geometry, object);
        rtcReleaseGeometry(geometry);
        check("adding a mesh");
    }

    // A sphere is Embree user geometry whose test is prism's (transform, motion and all), over
    // the world box prism's own index holds for it.
    void add_sphere_object(std::uint32_t object) {
        user_data_.push_back({this, object});
        RTCGeometry geometry = rtcNewGeometry(device_.get(), RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(geometry, 1);
        rtcSetGeometryUserData(geometry, &user_data_.back());
        rtcSetGeometryBoundsFunction(geometry, &sphere_bounds, nullptr);
        rtcSetGeometryIntersectFunction(geometry, &sphere_intersect);
        rtcSetGeometryOccludedFunction(geometry, &sphere_occluded);
        rtcCommitGeometry(geometry);
        rtcAttachGeometryByID(scene_.get(), geometry, object);
        rtcReleaseGeometry(geometry);
        check("adding a sphere");
    }

    static void sphere_bounds(const RTCBoundsFunctionArguments* args) {
        const auto* data = static_cast<const SphereUserData*>(args->geometryUserPtr);
        const Aabb<Real> box = data->self->placement(data->object).world_bounds;
        // Rounded outwards to float, so the box still holds the sphere.
        args->bounds_o->lower_x = next_down(float(box.min.x));
        args->bounds_o->lower_y = next_down(float(box.min.y));
        args->bounds_o->lower_z = next_down(float(box.min.z));
        args->bounds_o->upper_x = next_up(float(box.max.x));
        args->bounds_o->upper_y = next_up(float(box.max.y));
        args->bounds_o->upper_z = next_up(float(box.max.z));
    }

    static void sphere_intersect(const RTCIntersectFunctionNArguments* args) {
        if (!args->valid[0]) return;
        const auto* data = static_cast<const SphereUserData*>(args->geometryUserPtr);
        RTCRayN* rays = RTCRayHitN_RayN(args->rayhit, args->N);
        // The query's own ray in Real (Embree's copy is rounded to float: in double its origin
        // could lie inside the sphere a ray just left); Embree keeps the closest so far.
        Ray<Real> ray = *reinterpret_cast<const Context*>(args->context)->world_ray;
        Hit<Real> hit;
        if (!data->self->intersect_primitive(data->object, 0, ray, hit)) return;
        if (!(float(hit.t) <= RTCRayN_tfar(rays, args->N, 0))) return;
        RTCRayN_tfar(rays, args->N, 0) = float(hit.t);
        RTCHitN* embree_hit = RTCRayHitN_HitN(args->rayhit, args->N);
        RTCHitN_geomID(embree_hit, args->N, 0) = data->object;
        RTCHitN_primID(embree_hit, args->N, 0) = 0;
        RTCHitN_u(embree_hit, args->N, 0) = 0;
        RTCHitN_v(embree_hit, args->N, 0) = 0;
        RTCHitN_instID(embree_hit, args->N, 0, 0) = args->context->instID[0];
    }

    static void sphere_occluded(const RTCOccludedFunctionNArguments* args) {
        if (!args->valid[0]) return;
        const auto* data = static_cast<const SphereUserData*>(args->geometryUserPtr);
        Ray<Real> ray = *reinterpret_cast<const Context*>(args->context)->world_ray;
        const Real t_max = ray.t_max;
        Hit<Real> hit;
        if (data->self->intersect_primitive(data->object, 0, ray, hit) && hit.t < t_max)
            RTCRayN_tfar(args->ray, args->N, 0) = -std::numeric_limits<float>::infinity();
    }

    static constexpr bool exact_filter = !std::is_same_v<Real, float>;

    // The context filter of a query: culling (camera rays, geometry/backface_culling.hpp), then
    // in double prism's test; none when neither applies.
    template <bool Cull, bool AnyHit>
    static RTCFilterFunctionN filter_for() {
        if constexpr (Cull || exact_filter) return &filter<Cull, AnyHit>;
        else return nullptr;
    }

    template <bool Cull, bool AnyHit>
    static void filter(const RTCFilterFunctionNArguments* args) {
        if (!args->valid[0]) return;
        const auto* context = reinterpret_cast<const Context*>(args->context);
        const unsigned instance = RTCHitN_instID(args->hit, args->N, 0, 0);
        const std::uint32_t object =
            instance != RTC_INVALID_GEOMETRY_ID ? instance : RTCHitN_geomID(args->hit, args->N, 0);
        const std::uint32_t primitive = RTCHitN_primID(args->hit, args->N, 0);
        if constexpr (Cull) {
            // prism's own orientation test, on prism's triangle and ray: with Embree's rounded
            // normal and ray, grazing triangles (hw1 rt_raven's) came out on the other side
            // (81.8 -> 72.7 dB).
            if (context->self->culled(object, primitive, *context->world_ray)) {
                args->valid[0] = 0;
                return;
            }
        }
        if constexpr (exact_filter) {
            Ray<Real> ray = *context->world_ray;
            const Real t_max = ray.t_max;
            Hit<Real> hit;
            const bool hit_by_prism = context->self->intersect_primitive(object, primitive, ray, hit);
            if (!hit_by_prism || (AnyHit && !(hit.t < t_max))) args->valid[0] = 0;
        }
    }

    PlaneSet<Real> planes_;
    DeviceHandle device_;
    SceneHandle scene_;
    std::vector<std::unique_ptr<SceneHandle>> mesh_scenes_;
    std::vector<SphereUserData> user_data_;  // reserved up front: Embree keeps pointers into it
};

}  // namespace prism
