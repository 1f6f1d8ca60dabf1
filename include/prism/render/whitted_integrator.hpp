// Recursive ray tracing as the course defines it (Whitted 1980 with Blinn-Phong shading):
// ambient + per-light diffuse and specular with shadow rays; mirror and conductor reflection
// (conductors weighted by their Fresnel reflectance); dielectric reflection and refraction with
// Fresnel weights, total internal reflection, and Beer's law attenuation inside the medium.
// The course's distribution effects ride on the same recursion (Cook, Porter and Carpenter
// 1984): one light sample per light and camera sample (area and environment lights), and
// Roughness perturbing each reflected and refracted direction once per camera sample.
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/geometry/backface_culling.hpp>
#include <prism/geometry/hit.hpp>
#include <prism/geometry/ray_batch.hpp>
#include <prism/light/light_sample.hpp>
#include <prism/light/light_set.hpp>
#include <prism/light/point_light.hpp>
#include <prism/light/point_light_lanes.hpp>
#include <prism/material/fresnel.hpp>
#include <prism/material/material.hpp>
#include <prism/memory/unconstructed.hpp>
#include <prism/render/integrator.hpp>
#include <prism/render/stored_whole.hpp>
#include <prism/sampling/sampler.hpp>
#include <prism/texture/mipmap.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cmath>
#include <optional>
#include <type_traits>
#include <variant>
#include <vector>

namespace prism {

// How a ray leaving a surface is kept from finding that surface again.
enum class RayOffset {
    // From the hit point's floating-point error bound (SceneSurfaces::spawn_origin): no
    // scene-tuned number, right at any scale and in float and double alike.
    error_bound,
    // The course's: ShadowRayEpsilon along the shading normal, for every secondary ray.
    scene_epsilon,
};

// The ray leaving `point` along `direction`, by `offset`; `normal` is the shading normal facing
// the incoming ray (the scene-epsilon mode offsets along it, to the side the ray leaves by).
// Both integrators spawn their secondary and shadow rays through it. Inlined, so that its fields
// stay in registers for stored_whole (render/stored_whole.hpp): called out of line, it answered
// through memory, and the copy of that answer into trace's argument waited for its stores.
template <Scalar Real, class Geometry>
PRISM_FORCE_INLINE inline Ray<Real> leaving_ray(const Geometry& geometry, RayOffset offset, Real epsilon,
                                                    const SurfacePoint<Real>& point, const Vec3<Real>& normal,
                                                    const Vec3<Real>& direction, Real time) {
    Ray<Real> ray{Vec3<Real>(0), direction, Real(0), infinity<Real>, time};
    if (offset == RayOffset::error_bound) {
        ray.origin = geometry.spawn_origin(point, direction);
    } else {
        ray.origin = point.position + (glm::dot(direction, normal) >= 0 ? normal : -normal) * epsilon;
    }
    return ray;
}

struct IntegratorSettings {
    int max_recursion_depth = 0;
    double shadow_ray_epsilon = 1e-3;  // RayOffset::scene_epsilon's offset
    RayOffset ray_offset = RayOffset::scene_epsilon;
    // What camera rays skip when they meet it from behind; secondary rays see every back face.
    BackfaceCulling backface_culling = BackfaceCulling::triangles;
};

// A surface's textures as the integrator uses them; `NoTextures` is the policy of renderers
// compiled without texture support, and costs nothing.
// The interface is TextureSet's (texture/texture_set.hpp): apply() changes the material and
// the shading normal and may give an unshaded colour (replace_all); background() is the
// replace_background texture at the pixel.
template <Scalar Real>
struct NoTextures {
    explicit NoTextures(const scene::Scene&) {}
    bool apply(SurfacePoint<Real>&, const Material<Real>&, Vec3<Real>&, const RayCone<Real>&) const { return false; }
    std::optional<Vec3<Real>> background(const Vec2<Real>&) const { return {}; }
};

// Whether a texture policy can change what a hit looks like: NoTextures cannot, so an
// integrator under it reads the material in place and skips the surface's (u, v) and tangents.
template <class Textures, class Real>
inline constexpr bool textured = !std::is_same_v<Textures, NoTextures<Real>>;

// The surface point at a hit, with (u, v) and tangents only where textures may read them, and
// the exact point with its error bound only where rays leave by it (RayOffset::error_bound).
// Inlined into trace, so that surface<false> is (SceneSurfaces::surface).
template <bool Textured, Scalar Real, class Geometry>
PRISM_FORCE_INLINE inline SurfacePoint<Real> shading_surface(const Geometry& geometry, const Ray<Real>& ray, const Hit<Real>& hit,
                                   RayOffset offset) {
    return geometry.template surface<Textured>(ray, hit, offset == RayOffset::error_bound);
}

// The same for an integrator's texture set: a renderer compiled with textures parametrises its
// surfaces only when the scene has some. Without, nothing reads (u, v) or the tangents, and a
// sphere's (its acos, atan2 and sincos) were 4% of hw7 path_glass's time in the renderer that
// every path-traced scene takes (all features compiled in).
template <class Textures, Scalar Real, class Geometry>
PRISM_FORCE_INLINE inline SurfacePoint<Real> shading_surface(const Geometry& geometry, const Textures& textures,
                                                                 const Ray<Real>& ray, const Hit<Real>& hit,
                                                                 RayOffset offset) {
    if constexpr (textured<Textures, Real>) {
        if (!textures.empty()) return shading_surface<true>(geometry, ray, hit, offset);
    }
    return shading_surface<false>(geometry, ray, hit, offset);
}

// What escaping rays see, for renderers without environment lights: the background colour for
// primary rays, nothing for the others.
template <Scalar Real>
struct NoEnvironment {
    bool present() const { return false; }
    Vec3<Real> radiance(const Vec3<Real>&) const { return Vec3<Real>(0); }
};

// Perturbs a unit direction by the course's glossy model: r' = normalize(r + roughness (a u +
// b v)) with a, b uniform in [-1/2, 1/2) and (u, v) an orthonormal basis perpendicular to r,
// built from r with its smallest component set to 1 (the course's construction).
template <Scalar Real>
Vec3<Real> perturb(const Vec3<Real>& direction, Real roughness, const Vec2<Real>& sample) {
    Vec3<Real> helper = direction;
    const Vec3<Real> magnitude = abs_each(direction);
    if (magnitude.x <= magnitude.y && magnitude.x <= magnitude.z) helper.x = 1;
    else if (magnitude.y <= magnitude.z) helper.y = 1;
    else helper.z = 1;
    const Vec3<Real> u = unit_vector(glm::cross(helper, direction));
    const Vec3<Real> v = glm::cross(direction, u);
    return unit_vector(direction + roughness * ((sample.x - Real(0.5)) * u + (sample.y - Real(0.5)) * v));
}

template <Scalar Real, class Geometry, class LightSetT, class Textures = NoTextures<Real>,
          class Environment = NoEnvironment<Real>, class Sampler = IndependentSampler>
class WhittedIntegrator {
    // The error-bounded origins of the rays leaving one surface point, one per side they leave
    // by (SceneSurfaces::spawn_side), each computed for the first ray that needs it: the shadow
    // rays to every light and the reflected and refracted rays share them. A mirror's reflected
    // ray leaves by the side its lit shadow rays left by, so it no longer computes the origin
    // again (offset_ray_origin was 3.7% of hw1 simple_reflectance's samples).
    struct SpawnOrigins {
        std::array<Vec3<Real>, 4> origin;
        unsigned known = 0;
    };

public:
    WhittedIntegrator(const Geometry& geometry, const LightSetT& lights, const std::vector<Material<Real>>& materials,
                      const Textures& textures, const Environment& environment, const Vec3<Real>& ambient_light,
                      const Vec3<Real>& background, const IntegratorSettings& settings)
        : geometry_(geometry), lights_(lights), materials_(materials), textures_(textures), environment_(environment),
          ambient_light_(ambient_light), background_(background), settings_(settings),
          epsilon_(Real(settings.shadow_ray_epsilon)), prelit_count_(count_prelit(lights)) {}

    // What a camera ray carries down its recursion besides the ray itself.
    struct CameraPath {
        Sampler& sampler;    // the pixel's sampler (sampling/sampler.hpp)
        Vec2<Real> pixel_uv; // the pixel's position in [0, 1]^2 from the top left (background texture)
        Real spread = 0;     // the pixel's angular size: the ray cone's spread (trilinear textures)
    };

    // Radiance arriving along a camera ray with a unit direction.
    Vec3<Real> radiance(const Ray<Real>& ray, CameraPath& path) const { return trace(ray, 0, path, Real(0)); }

    // Camera rays several at a time: first their closest hits, as one batch through the query
    // seam (camera_hits: the hits radiance's own intersection finds, each ray's t_max lowered as
    // it lowers it), then each ray's radiance from its hit (radiance_at), the rest of
    // radiance's work. The index decides how side by side the hits are found.
    bool batches_camera_rays(const scene::Camera&) const { return true; }
    std::uint32_t camera_hits(Ray<Real>* rays, Hit<Real>* hits, int count) const {
        return geometry_.intersect(RayBatch<Real>::all(rays, count, settings_.backface_culling), hits);
    }
    Vec3<Real> radiance_at(const Ray<Real>& ray, const Hit<Real>& hit, bool found, CameraPath& path) const {
        if (!found) return escaped(ray.direction, 0, path.pixel_uv);
        return shade(ray, hit, 0, path, Real(0));
    }

    // radiance_at for a row's camera rays together (count <= row_width), in point-lit
    // renderers without textures: every hit's shadow rays are made first, then each light's
    // are tested across the row as one batch, then each point is shaded; the mirrors' and
    // conductors' reflected rays then go on as a row of their own (shade_row). The same draws,
    // rays, tests and sums as radiance_at, so the same bits. `make_path(i)`: ray i's
    // CameraPath (its pixel's stream, by reference).
    // Other renderers (textures, other lights) take the rays one by one.
    static constexpr int row_width = 16;
    static constexpr std::size_t row_lights = 8;
    static constexpr bool shades_rows = !textured<Textures, Real> && std::is_same_v<LightSetT, LightSet<Real, PointLight>>;
    template <class MakePath>
    void radiance_row(const Ray<Real>* rays, const Hit<Real>* hits, std::uint32_t found, int count, MakePath make_path,
                      Vec3<Real>* radiance) const {
        const std::vector<PointLight<Real>>* lights = nullptr;
        if constexpr (shades_rows) lights = lights_.template of_type<PointLight>();
        if (!lights || lights->size() > row_lights) {
            for (int i = 0; i < count; ++i) {
                CameraPath path = make_path(i);
                radiance[i] = radiance_at(rays[i], hits[i], (found >> i) & 1, path);
            }
            return;
        }
        if constexpr (shades_rows) {
            Unconstructed<CameraPath, row_width> paths;
            for (int i = 0; i < count; ++i) paths.make_from(std::size_t(i), [&] { return make_path(i); });
            shade_row(rays, hits, found, count, paths.data(), nullptr, 0, radiance);
        }
    }

    // radiance_at for `count` (<= prelit_width) camera rays of one pixel's samples, which
    // draw from one sampler (`path`), each after `start_sample(i)` readies it for rays[i]:
    // radiance[i] for rays[i]. A stream's draws depend on every earlier sample's (its
    // start_sample does nothing), another sampler's on the sample alone, but the lights that draw nothing (point,
    // directional, spot: `sample(at)` alone) need no draw to be sampled: their shadow rays from
    // the samples' camera hits are made first, up to prelit_lights such lights, and tested
    // light by light as one batch each (the samples of a pixel meet nearly one point, so their
    // rays reach the same nodes: the index takes them side by side). Then each sample is
    // shaded as shade shades it, its stream stepping past those lights' draws in their turn.
    // The same rays, tests, draws and sums as radiance_at, so the same bits. Only where
    // prelights(): the scene has such a light.
    static constexpr int prelit_width = 16;
    static_assert(prelit_width == row_width, "radiances_at makes point lights' rays as rows do (point_light_lanes)");
    static constexpr std::size_t prelit_lights = 8;
    bool prelights() const { return prelit_count_ > 0; }
    template <class StartSample>
    void radiances_at(const Ray<Real>* rays, const Hit<Real>* hits, std::uint32_t found, int count, CameraPath& path,
                      StartSample start_sample, Vec3<Real>* radiance) const;

private:

    static std::size_t count_prelit(const LightSetT& lights) {
        std::size_t count = 0;
        lights.for_each([&](const auto& light) {
            if constexpr (sampled_without_draws<std::decay_t<decltype(light)>, Real>) ++count;
        });
        return std::min(count, prelit_lights);
    }

    // How deep radiance_row follows a row's mirror and conductor reflections as rows (a
    // shade_row frame each, some 20 kB of a worker's stack); deeper ones are traced one by one.
    static constexpr int row_depth = 8;

    // radiance_row's rows at `depth`: rays[i] has travelled `travelled[i]` before its origin
    // (camera rays: `travelled` null, none, and depth 0) and draws from paths[i]. shade's work,
    // pass by pass across the row. One function for the camera rows and the reflected rows: a
    // copy for each was 12 kB of every point-lit renderer's code. Called only where
    // shades_rows (under if constexpr): a trailing requires-clause on a member that is not a
    // template, defined out of line, is more than clang 14 can match to its declaration.
    void shade_row(const Ray<Real>* rays, const Hit<Real>* hits, std::uint32_t found, int count, CameraPath* paths,
                   const Real* travelled, int depth, Vec3<Real>* radiance) const;

    // The shading points of a row, SoA, for point_light_lanes.
    using RowPoints = ShadingRow<Real, row_width>;
    // Where rays leave by the scene's epsilon, that epsilon (point_light_lanes).
    std::optional<Real> scene_epsilon() const {
        if (settings_.ray_offset == RayOffset::error_bound) return std::nullopt;
        return epsilon_;
    }

    // `travelled`: the distance from the camera to the ray's origin along the path, which widens
    // the ray cone like a pinhole's (mirrors are treated as flat: Ray Tracing Gems ch. 20's
    // simplest variant).
    Vec3<Real> trace(Ray<Real> ray, int depth, CameraPath& path, Real travelled) const {
        Hit<Real> hit;
        if (!intersect(ray, depth, hit)) return escaped(ray.direction, depth, path.pixel_uv);
        return shade(ray, hit, depth, path, travelled);
    }

    // The radiance leaving the hit `hit` of `ray` back along it: trace's work past the
    // intersection.
    PRISM_FORCE_INLINE Vec3<Real> shade(const Ray<Real>& ray, const Hit<Real>& hit, int depth, CameraPath& path,
                                            Real travelled) const {
        SurfacePoint<Real> point = shading_surface(geometry_, textures_, ray, hit, settings_.ray_offset);
        // Textures change a copy; without them the material is read where it is stored.
        std::conditional_t<textured<Textures, Real>, Material<Real>, const Material<Real>&> material =
            materials_[point.material];
        travelled += hit.t;
        const RayCone<Real> cone{travelled * path.spread, std::abs(glm::dot(ray.direction, point.shading_normal))};
        if (Vec3<Real> unshaded; textures_.apply(point, material, unshaded, cone)) return unshaded;
        Sampler& sampler = path.sampler;
        const Vec3<Real>& d = ray.direction;
        const bool front_face = glm::dot(point.geometric_normal, d) < 0;
        // Shading uses the normal on the side the ray arrives from.
        const Vec3<Real> normal = front_face ? point.shading_normal : -point.shading_normal;

        // A ray travelling inside a dielectric sees the interface from within, where no light
        // reaches directly: the course shades only the outside (scienceTree_glass: 30.5 dB
        // with inside shading, 58.5 dB without).
        const bool inside_medium = !front_face && material.type == scene::MaterialType::dielectric;
        Vec3<Real> color(0);
        SpawnOrigins origins;
        if (!inside_medium) {
            // Object lights (LightMesh, LightSphere) are seen by every ray that finds them.
            color = geometry_.emitted(hit.object) + material.ambient * ambient_light_;
            color += direct_lighting(point, normal, -d, material, sampler, origins);
        }

        return reflect_and_absorb(ray, hit, point, material, normal, front_face, inside_medium, color, depth, path,
                                  travelled, origins);
    }

    // shade, out of line: for shade_row's reflections past row_depth, which inlining all of
    // shade made too large for GCC to keep the row's own point and shading code inline.
    [[gnu::noinline]] Vec3<Real> shade_apart(const Ray<Real>& ray, const Hit<Real>& hit, int depth, CameraPath& path,
                                             Real travelled) const {
        return shade(ray, hit, depth, path, travelled);
    }

    // shade's work past the direct lighting: the reflected (and refracted) rays traced, and
    // Beer's law inside a medium; `color` is the point's own (emitted, ambient, direct).
    PRISM_FORCE_INLINE Vec3<Real> reflect_and_absorb(const Ray<Real>& ray, const Hit<Real>& hit,
                                                         const SurfacePoint<Real>& point, const Material<Real>& material,
                                                         const Vec3<Real>& normal, bool front_face, bool inside_medium,
                                                         Vec3<Real> color, int depth, CameraPath& path, Real travelled,
                                                         SpawnOrigins& origins) const {
        const Vec3<Real>& d = ray.direction;
        // Blinn-Phong surfaces spawn no rays; the others reflect (and dielectrics refract).
        if (depth < settings_.max_recursion_depth && material.type != scene::MaterialType::blinn_phong) {
            using scene::MaterialType;
            Real cos_incident;
            const Ray<Real> reflection = reflection_of(ray, point, material, normal, path, origins, cos_incident);
            switch (material.type) {
                case MaterialType::blinn_phong: break;
                case MaterialType::mirror:
                case MaterialType::conductor:
                    color += reflection_weight(material, cos_incident) * trace(reflection, depth + 1, path, travelled);
                    break;
                case MaterialType::dielectric:
                    color += dielectric(point, d, normal, cos_incident, front_face, material, reflection, depth,
                                        path, travelled, origins);
                    break;
            }
        }

        // Beer's law: a ray that reached this surface from inside travelled hit.t through it.
        if (inside_medium) {
            const Vec3<Real> transmittance = glm::exp(-material.absorption_coefficient * hit.t);
            color *= transmittance;
        }
        return color;
    }

    // The ray a surface that is not Blinn-Phong reflects toward (perturbed by its roughness,
    // drawing from the path's stream), and the cosine of incidence it was made with.
    PRISM_FORCE_INLINE Ray<Real> reflection_of(const Ray<Real>& ray, const SurfacePoint<Real>& point,
                                                   const Material<Real>& material, const Vec3<Real>& normal,
                                                   CameraPath& path, SpawnOrigins& origins, Real& cos_incident) const {
        const Vec3<Real>& d = ray.direction;
        cos_incident = -glm::dot(d, normal);
        Vec3<Real> reflected = d + 2 * cos_incident * normal;
        if (material.roughness > 0) reflected = perturb(reflected, material.roughness, path.sampler.template uniform2<Real>());
        return stored_whole(leaving(point, normal, reflected, ray.time, origins));
    }

    // What a mirror's or a conductor's reflected radiance is multiplied by: its MirrorReflectance,
    // times the conductor's Fresnel reflectance (fresnel * mirror, then the radiance: the
    // products in the order the expression always took them).
    PRISM_FORCE_INLINE Vec3<Real> reflection_weight(const Material<Real>& material, Real cos_incident) const {
        if (material.type != scene::MaterialType::conductor) return material.mirror;
        const Real fresnel =
            fresnel_conductor(std::max(cos_incident, Real(0)), material.refraction_index, material.absorption_index);
        return fresnel * material.mirror;
    }

    bool intersect(Ray<Real>& ray, int depth, Hit<Real>& hit) const {
        return closest_hit(geometry_, ray, hit, culling_at_depth(settings_.backface_culling, depth));
    }

    // A ray that meets nothing: primary rays show the background (texture, environment or
    // colour); the course's secondary rays bring back nothing unless an environment surrounds
    // the scene.
    Vec3<Real> escaped(const Vec3<Real>& direction, int depth, const Vec2<Real>& pixel_uv) const {
        if (depth == 0) {
            if (const std::optional<Vec3<Real>> texture = textures_.background(pixel_uv)) return *texture;
        }
        if (environment_.present()) return environment_.radiance(direction);
        return depth == 0 ? background_ : Vec3<Real>(0);
    }

    // The ray leaving `point` along `direction`, as leaving_ray gives it, from the origin
    // `origins` holds for its side where rays leave by the error bound. spawn_origin depends on
    // the direction only through that side, so the ray is the one leaving_ray would give, bit
    // for bit. Inlined for stored_whole, as leaving_ray is.
    PRISM_FORCE_INLINE Ray<Real> leaving(const SurfacePoint<Real>& point, const Vec3<Real>& normal,
                                             const Vec3<Real>& direction, Real time, SpawnOrigins& origins) const {
        if (settings_.ray_offset == RayOffset::error_bound) {
            const int side = geometry_.spawn_side(point, direction);
            if (!(origins.known & (1u << side))) {
                origins.origin[std::size_t(side)] = geometry_.spawn_origin(point, direction);
                origins.known |= 1u << side;
            }
            return Ray<Real>{origins.origin[std::size_t(side)], direction, Real(0), infinity<Real>, time};
        }
        return leaving_ray(geometry_, settings_.ray_offset, epsilon_, point, normal, direction, time);
    }

    // `origins`: the point's shadow rays take their origins from it and leave theirs in it for
    // the reflected and refracted rays.
    Vec3<Real> direct_lighting(const SurfacePoint<Real>& point, const Vec3<Real>& normal, const Vec3<Real>& to_viewer,
                               const Material<Real>& material, Sampler& sampler, SpawnOrigins& origins) const {
        if constexpr (std::is_same_v<LightSetT, LightSet<Real, PointLight>>) {
            const std::vector<PointLight<Real>>& lights = *lights_.template of_type<PointLight>();
            if (lights.size() > 1)
                return point_lighting_batched(point, normal, to_viewer, material, sampler, origins, lights);
        }
        Vec3<Real> color(0);
        lights_.for_each([&](const auto& light) { light_term(light, point, normal, to_viewer, material, sampler, origins, color); });
        return color;
    }

    // One light's term of direct_lighting's sum, added to `color` where its shadow ray is not
    // blocked.
    template <class L>
    PRISM_FORCE_INLINE void light_term(const L& light, const SurfacePoint<Real>& point, const Vec3<Real>& normal,
                                           const Vec3<Real>& to_viewer, const Material<Real>& material, Sampler& sampler,
                                           SpawnOrigins& origins, Vec3<Real>& color) const {
        const Vec3<Real>& position = point.position;
        // A light that takes no sample (point, directional, spot: sample(at) alone) gets none
        // drawn, but the stream steps past its two numbers, so that every later draw is the
        // one it was (the images stay the same).
        const ShadingFrame<Real> at{position, normal};
        const LightSample<Real> sample = [&] {
            if constexpr (sampled_without_draws<L, Real>) {
                sampler.template skip<Real>(2);
                return light.sample(at);
            } else {
                return light.sample(at, sampler.template uniform2<Real>());
            }
        }();
        const Real cos_light = glm::dot(normal, sample.direction);
        if (cos_light <= 0) return;
        // The shadow ray leaves the offset origin aimed at the light, and anything nearer than
        // the light's distance from the shading point blocks it. So a surface through the
        // light itself blocks it for every point, not by rounding (mirror_room's ceiling
        // holds a light: 20.3 dB with a per-pixel coin flip, 64.5 dB consistent).
        Ray<Real> shadow = leaving(point, normal, sample.direction, point.time, origins);
        if (!std::isinf(sample.distance))
            shadow.direction = unit_vector(position + sample.direction * sample.distance - shadow.origin);
        shadow.t_max = sample.distance;
        // An object light's own surface is at the far end and is geometry: stop short of it,
        // as the path tracer does, or the light shadows itself (every point black, but for
        // rounding). Area lights are no geometry, so their rule above stays.
        if constexpr (L::kind == scene::LightKind::object)
            shadow.t_max = glm::length(position + sample.direction * sample.distance - shadow.origin) * (1 - Real(1e-4));
        if (blocked(geometry_, shadow)) return;
        color += reflected(material, normal, to_viewer, sample, cos_light);
    }

    // Several point lights' shadow rays made before the first is tested, and tested in one
    // batch (the query seam), up to eight at a time; then the lit ones shaded in
    // the lights' order. The chains of square roots and divisions that aim each ray (the
    // light's sample, the aim from the offset origin) overlap instead of each waiting for the
    // previous light's test. The same draws (the stream only steps past two numbers a light),
    // rays, tests and sum as direct_lighting's loop, so the same bytes. Out of line and only
    // for two lights or more: the one-light renderer's loop, its inlined occluded included,
    // stays as it was (whole9: batching in the loop itself cost one-light scenes 2-7%).
    template <class PointLights>
    [[gnu::noinline]] Vec3<Real> point_lighting_batched(const SurfacePoint<Real>& point, const Vec3<Real>& normal,
                                                        const Vec3<Real>& to_viewer, const Material<Real>& material,
                                                        Sampler& sampler, SpawnOrigins& origins, const PointLights& lights) const {
        constexpr std::size_t batch = 8;
        Vec3<Real> color(0);
        const Vec3<Real>& position = point.position;
        const ShadingFrame<Real> at{position, normal};
        for (std::size_t first = 0; first < lights.size(); first += batch) {
            const std::size_t count = std::min(batch, lights.size() - first);
            // Field by field: a whole LightSample or Ray copied into the arrays was read back
            // wider than its parts had been written (a failed store forward, a fifth of hw1
            // simple_reflectance's samples of this function).
            std::array<Vec3<Real>, batch> directions, radiances;
            std::array<Real, batch> cosines;
            // Made for the lit lanes alone, the batch's active ones (memory/unconstructed.hpp).
            Unconstructed<Ray<Real>, batch> shadows;
            std::uint32_t lit = 0;
            for (std::size_t i = 0; i < count; ++i) {
                sampler.template skip<Real>(2);
                const LightSample<Real> sample = lights[first + i].sample(at);
                directions[i] = sample.direction;
                radiances[i] = sample.radiance;
                cosines[i] = glm::dot(normal, sample.direction);
                if (cosines[i] <= 0) continue;
                make_shadow_ray(shadows.make(i), point, normal, sample, origins);
                lit |= std::uint32_t(1) << i;
            }
            lit &= ~geometry_.occluded(RayBatch<Real>{shadows.data(), int(count), lit});
            for (; lit != 0; lit &= lit - 1) {
                const std::size_t i = std::size_t(std::countr_zero(lit));
                LightSample<Real> sample;
                sample.direction = directions[i];
                sample.radiance = radiances[i];
                color += reflected(material, normal, to_viewer, sample, cosines[i]);
            }
        }
        return color;
    }

    // A point light's shadow ray from `point` into `made`, as direct_lighting's loop makes it:
    // from the offset origin, aimed at the light from there, up to the light's distance.
    // Field by field: a whole Ray copied into the batches' arrays was read back wider than its
    // parts had been written (a failed store forward, a fifth of hw1 simple_reflectance's
    // samples of point_lighting_batched).
    PRISM_FORCE_INLINE void make_shadow_ray(Ray<Real>& made, const SurfacePoint<Real>& point, const Vec3<Real>& normal,
                                                const LightSample<Real>& sample, SpawnOrigins& origins) const {
        const Ray<Real> shadow = leaving(point, normal, sample.direction, point.time, origins);
        made.origin = shadow.origin;
        made.direction = std::isinf(sample.distance)
                             ? shadow.direction
                             : unit_vector(point.position + sample.direction * sample.distance - shadow.origin);
        made.t_min = shadow.t_min;
        made.t_max = sample.distance;
        made.time = shadow.time;
    }

    // One light's reflected radiance at a point its shadow ray found lit.
    PRISM_FORCE_INLINE Vec3<Real> reflected(const Material<Real>& material, const Vec3<Real>& normal,
                                                const Vec3<Real>& to_viewer, const LightSample<Real>& sample,
                                                Real cos_light) const {
        if (material.brdf_given)
            return evaluate_brdf(material, normal, sample.direction, to_viewer) * cos_light * sample.radiance;
        // No BRDF: hw1-hw5's Blinn-Phong, kept in this form so their images stay bit-identical.
        const Vec3<Real> half_vector = unit_vector(sample.direction + to_viewer);
        const Real cos_half = std::max(glm::dot(normal, half_vector), Real(0));
        // A material without a specular colour (hw1 simple_reflectance's floor) skips the
        // power where it is finite, a base in [0, 1] and an exponent of at least 0: the term is
        // then specular * 0, the signed zeros the product gives (a NaN half vector, a base
        // rounded past 1 or a negative exponent still take std::pow). So does one whose power
        // cannot change the sum (blinn_phong_power_negligible: most points away from a highlight).
        const Vec3<Real> diffuse = material.diffuse * cos_light;
        Vec3<Real> specular = material.specular * Real(0);
        if ((material.specular != Vec3<Real>(0) || !(cos_half <= 1) || !(material.phong_exponent >= 0)) &&
            !blinn_phong_power_negligible(material, cos_half, diffuse))
            specular = material.specular * blinn_phong_power(cos_half, material.phong_exponent);
        return (diffuse + specular) * sample.radiance;
    }

    Vec3<Real> dielectric(const SurfacePoint<Real>& point, const Vec3<Real>& d, const Vec3<Real>& normal,
                          Real cos_incident, bool front_face, const Material<Real>& material,
                          const Ray<Real>& reflection, int depth, CameraPath& path, Real travelled,
                          SpawnOrigins& origins) const {
        const Real n1 = front_face ? Real(1) : material.refraction_index;
        const Real n2 = front_face ? material.refraction_index : Real(1);
        const Real ratio = n1 / n2;
        const Real sin2_transmitted = ratio * ratio * (1 - cos_incident * cos_incident);
        if (sin2_transmitted >= 1) return trace(reflection, depth + 1, path, travelled);  // total internal reflection
        const Real cos_transmitted = std::sqrt(1 - sin2_transmitted);
        const Real fresnel = fresnel_dielectric(cos_incident, cos_transmitted, n1, n2);
        Vec3<Real> transmitted = unit_vector(ratio * d + (ratio * cos_incident - cos_transmitted) * normal);
        Sampler& sampler = path.sampler;
        if (material.roughness > 0) transmitted = perturb(transmitted, material.roughness, sampler.template uniform2<Real>());
        const Ray<Real> refraction = stored_whole(leaving(point, normal, transmitted, reflection.time, origins));
        Vec3<Real> through = (1 - fresnel) * trace(refraction, depth + 1, path, travelled);
        // Pre-2020 scenes describe glass by a Transparency colour that filters what passes.
        if (material.transparency != Vec3<Real>(0)) through *= material.transparency;
        return fresnel * trace(reflection, depth + 1, path, travelled) + through;
    }

    const Geometry& geometry_;
    const LightSetT& lights_;
    const std::vector<Material<Real>>& materials_;
    const Textures& textures_;
    const Environment& environment_;
    Vec3<Real> ambient_light_;
    Vec3<Real> background_;
    IntegratorSettings settings_;
    Real epsilon_;
    std::size_t prelit_count_;  // the lights radiances_at samples first (count_prelit)
};

// The Config policy that renders with the course's recursive ray tracer.
struct Whitted {
    template <Scalar Real, class Geometry, class LightSetT, class Textures, class Environment, class Sampler>
    using Type = WhittedIntegrator<Real, Geometry, LightSetT, Textures, Environment, Sampler>;

    // Not scenes with a path-traced camera: those need the PathTracer policy.
    static constexpr bool covers(const scene::Needs& needs) { return !needs.path_tracing; }
};

}  // namespace prism

#include <prism/render/whitted_rows.hpp>
