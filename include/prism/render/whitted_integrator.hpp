// Recursive ray tracing as the course defines it (Whitted 1980 with Blinn-Phong shading):
// ambient + per-light diffuse and specular with shadow rays; mirror and conductor reflection
// (conductors weighted by their Fresnel reflectance); dielectric reflection and refraction with
// Fresnel weights, total internal reflection, and Beer's law attenuation inside the medium.
// The course's distribution effects ride on the same recursion (Cook, Porter and Carpenter
// 1984): one light sample per light and camera sample (area and environment lights), and
// Roughness perturbing each reflected and refracted direction once per camera sample.
#pragma once

#include <prism/geometry/backface_culling.hpp>
#include <prism/geometry/hit.hpp>
#include <prism/geometry/ray_batch.hpp>
#include <prism/light/light_sample.hpp>
#include <prism/light/light_set.hpp>
#include <prism/light/point_light.hpp>
#include <prism/material/fresnel.hpp>
#include <prism/material/material.hpp>
#include <prism/memory/unconstructed.hpp>
#include <prism/simd/pack.hpp>
#include <prism/render/integrator.hpp>
#include <prism/render/stored_whole.hpp>
#include <prism/sampling/random.hpp>
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
    // From the hit point's floating-point error bound (SceneGeometry::spawn_origin): no
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
[[gnu::always_inline]] inline Ray<Real> leaving_ray(const Geometry& geometry, RayOffset offset, Real epsilon,
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
// the shading normal and may return an unshaded colour (replace_all); background() is the
// replace_background texture at the pixel.
template <Scalar Real>
struct NoTextures {
    explicit NoTextures(const scene::Scene&) {}
    std::optional<Vec3<Real>> apply(SurfacePoint<Real>&, const Material<Real>&, const RayCone<Real>&) const { return {}; }
    std::optional<Vec3<Real>> background(const Vec2<Real>&) const { return {}; }
};

// Whether a texture policy can change what a hit looks like: NoTextures cannot, so an
// integrator under it reads the material in place and skips the surface's (u, v) and tangents.
template <class Textures, class Real>
inline constexpr bool textured = !std::is_same_v<Textures, NoTextures<Real>>;

// The surface point at a hit, with (u, v) and tangents only where textures may read them, and
// the exact point with its error bound only where rays leave by it (RayOffset::error_bound).
// Inlined into trace, so that surface<false> is (SceneGeometry::surface).
template <bool Textured, Scalar Real, class Geometry>
[[gnu::always_inline]] inline SurfacePoint<Real> shading_surface(const Geometry& geometry, const Ray<Real>& ray, const Hit<Real>& hit,
                                   RayOffset offset) {
    return geometry.template surface<Textured>(ray, hit, offset == RayOffset::error_bound);
}

// The same for an integrator's texture set: a renderer compiled with textures parametrises its
// surfaces only when the scene has some. Without, nothing reads (u, v) or the tangents, and a
// sphere's (its acos, atan2 and sincos) were 4% of hw7 path_glass's time in the renderer that
// every path-traced scene takes (all features compiled in).
template <class Textures, Scalar Real, class Geometry>
[[gnu::always_inline]] inline SurfacePoint<Real> shading_surface(const Geometry& geometry, const Textures& textures,
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
          class Environment = NoEnvironment<Real>>
class WhittedIntegrator {
    // The error-bounded origins of the rays leaving one surface point, one per side they leave
    // by (SceneGeometry::spawn_side), each computed for the first ray that needs it: the shadow
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
        Random& random;      // the pixel's stream
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
            shade_row<true>(rays, hits, found, count, paths.data(), nullptr, 0, radiance);
        }
    }

    // radiance_at for `count` (<= prelit_width) camera rays of one pixel's samples, which
    // draw from one stream (`path`), in their order: radiance[i] for rays[i]. Each sample's
    // draws depend on every earlier sample's, but the lights that draw nothing (point,
    // directional, spot: `sample(at)` alone) need no draw to be sampled: their shadow rays from
    // the samples' camera hits are made first, up to prelit_lights such lights, and tested
    // light by light as one batch each (the samples of a pixel meet nearly one point, so their
    // rays reach the same nodes: the index takes them side by side). Then each sample is
    // shaded as shade shades it, its stream stepping past those lights' draws in their turn.
    // The same rays, tests, draws and sums as radiance_at, so the same bits. Only where
    // prelights(): the scene has such a light.
    static constexpr int prelit_width = 16;
    static_assert(prelit_width == row_width, "radiances_at makes point lights' rays as rows do (light_lanes)");
    static constexpr std::size_t prelit_lights = 8;
    bool prelights() const { return prelit_count_ > 0; }
    void radiances_at(const Ray<Real>* rays, const Hit<Real>* hits, std::uint32_t found, int count, CameraPath& path,
                      Vec3<Real>* radiance) const
    {
        // shade's state at a camera hit up to its direct lighting (the point made in place).
        struct PrelitPoint {
            SurfacePoint<Real> point;
            Vec3<Real> normal{0};
            SpawnOrigins origins{};
            Real travelled = 0;
            std::uint32_t visible = 0;  // bit k: prelit light k's shadow ray is made and reaches it
            bool front_face = false, inside_medium = false;
        };
        Unconstructed<PrelitPoint, prelit_width> points;
        // Textures change a copy of the material; without them it is read where it is stored.
        std::conditional_t<textured<Textures, Real>, Unconstructed<Material<Real>, prelit_width>, std::monostate> copies;
        const auto material_of = [&](int i) -> decltype(auto) {
            if constexpr (textured<Textures, Real>) return copies[std::size_t(i)];
            else return static_cast<const Material<Real>&>(materials_[points[std::size_t(i)].point.material]);
        };
        std::uint32_t shading = 0;  // the samples shaded below (not escaped, not unshaded by a texture)
        std::uint32_t lighting = 0;  // the shading samples lit directly (outside a medium)
        for (int i = 0; i < count; ++i) {
            if (!((found >> i) & 1)) {
                radiance[i] = escaped(rays[i].direction, 0, path.pixel_uv);
                continue;
            }
            const Ray<Real>& ray = rays[i];
            PrelitPoint& at = points.make_from(std::size_t(i), [&] {
                return PrelitPoint{shading_surface(geometry_, textures_, ray, hits[i], settings_.ray_offset)};
            });
            if constexpr (textured<Textures, Real>) copies.make(std::size_t(i), materials_[at.point.material]);
            at.travelled = Real(0) + hits[i].t;
            const RayCone<Real> cone{at.travelled * path.spread, std::abs(glm::dot(ray.direction, at.point.shading_normal))};
            if (const std::optional<Vec3<Real>> unshaded = textures_.apply(at.point, material_of(i), cone)) {
                radiance[i] = *unshaded;
                continue;
            }
            at.front_face = glm::dot(at.point.geometric_normal, ray.direction) < 0;
            at.normal = at.front_face ? at.point.shading_normal : -at.point.shading_normal;
            at.inside_medium = !at.front_face && material_of(i).type == scene::MaterialType::dielectric;
            shading |= std::uint32_t(1) << i;
            if (!at.inside_medium) lighting |= std::uint32_t(1) << i;
        }
        // Each prelit light's samples and shadow rays across the samples, the rays side by side.
        std::array<std::array<Vec3<Real>, prelit_width>, prelit_lights> directions, radiances;
        std::array<std::array<Real, prelit_width>, prelit_lights> cosines;
        std::size_t k = 0;
        std::optional<RowPoints> row;  // the lighting points SoA, for the first point light
        const auto origin_of = [&](std::size_t i, const Vec3<Real>& direction) {
            PrelitPoint& at = points[i];
            return leaving(at.point, at.normal, direction, at.point.time, at.origins).origin;
        };
        lights_.for_each([&](const auto& light) {
            if constexpr (draws_nothing<std::decay_t<decltype(light)>>) {
                if (k == prelit_lights || lighting == 0) return;
                const std::size_t j = k++;
                Unconstructed<Ray<Real>, prelit_width> shadows;
                std::array<int, prelit_width> owner;
                int n = 0;
                if constexpr (std::is_same_v<std::decay_t<decltype(light)>, PointLight<Real>>) {
                    // Point lights lane by lane, as shade_row makes them (light_lanes).
                    if (!row) {
                        row.emplace();
                        for (std::uint32_t rest = lighting; rest != 0; rest &= rest - 1) {
                            const int i = std::countr_zero(rest);
                            const PrelitPoint& at = points[std::size_t(i)];
                            for (int axis = 0; axis < 3; ++axis) {
                                row->position[axis][i] = at.point.position[axis];
                                row->normal[axis][i] = at.normal[axis];
                            }
                            row->time[i] = at.point.time;
                        }
                        row->shading = lighting;
                    }
                    Unconstructed<Ray<Real>, prelit_width> made;
                    const std::uint32_t lit =
                        light_lanes(light, *row, directions[j], radiances[j], cosines[j], made, origin_of);
                    for (std::uint32_t rest = lit; rest != 0; rest &= rest - 1) {
                        const int i = std::countr_zero(rest);
                        shadows.make(std::size_t(n), made[std::size_t(i)]);
                        owner[std::size_t(n++)] = i;
                    }
                } else {
                    for (std::uint32_t rest = lighting; rest != 0; rest &= rest - 1) {
                        const int i = std::countr_zero(rest);
                        PrelitPoint& at = points[std::size_t(i)];
                        const LightSample<Real> sample = light.sample(ShadingFrame<Real>{at.point.position, at.normal});
                        directions[j][std::size_t(i)] = sample.direction;
                        radiances[j][std::size_t(i)] = sample.radiance;
                        cosines[j][std::size_t(i)] = glm::dot(at.normal, sample.direction);
                        if (cosines[j][std::size_t(i)] <= 0) continue;
                        make_shadow_ray(shadows.make(std::size_t(n)), at.point, at.normal, sample, at.origins);
                        owner[std::size_t(n++)] = i;
                    }
                }
                if (n == 0) return;
                const std::uint32_t blocked = geometry_.occluded(RayBatch<Real>::all(shadows.data(), n));
                for (int m = 0; m < n; ++m)
                    if (!((blocked >> m) & 1)) points[std::size_t(owner[std::size_t(m)])].visible |= std::uint32_t(1) << j;
            }
        });
        // Each sample shaded in its turn, as shade shades it.
        for (std::uint32_t rest = shading; rest != 0; rest &= rest - 1) {
            const int i = std::countr_zero(rest);
            PrelitPoint& at = points[std::size_t(i)];
            const Material<Real>& material = material_of(i);
            Vec3<Real> color(0);
            if (!at.inside_medium) {
                color = geometry_.emitted(hits[i].object) + material.ambient * ambient_light_;
                const Vec3<Real> to_viewer = -rays[i].direction;
                Vec3<Real> direct(0);
                std::size_t light_index = 0;  // among the prelit lights
                lights_.for_each([&](const auto& light) {
                    if constexpr (draws_nothing<std::decay_t<decltype(light)>>) {
                        if (light_index < prelit_lights) {
                            const std::size_t j = light_index++;
                            path.random.template skip<Real>(2);
                            if (!((at.visible >> j) & 1)) return;
                            LightSample<Real> sample;
                            sample.direction = directions[j][std::size_t(i)];
                            sample.radiance = radiances[j][std::size_t(i)];
                            direct += reflected(material, at.normal, to_viewer, sample, cosines[j][std::size_t(i)]);
                            return;
                        }
                    }
                    light_term(light, at.point, at.normal, to_viewer, material, path.random, at.origins, direct);
                });
                color += direct;
            }
            radiance[i] = reflect_and_absorb(rays[i], hits[i], at.point, material, at.normal, at.front_face,
                                             at.inside_medium, color, 0, path, at.travelled, at.origins);
        }
    }

    // The light types sampled without a draw (sample(at) alone).
    template <class L>
    static constexpr bool draws_nothing = requires(const L& light, const ShadingFrame<Real>& at) { light.sample(at); };

    static std::size_t count_prelit(const LightSetT& lights) {
        std::size_t count = 0;
        lights.for_each([&](const auto& light) {
            if constexpr (draws_nothing<std::decay_t<decltype(light)>>) ++count;
        });
        return std::min(count, prelit_lights);
    }

    // How deep radiance_row follows a row's mirror and conductor reflections as rows (a
    // shade_row frame each, some 20 kB of a worker's stack); deeper ones are traced one by one.
    static constexpr int row_depth = 8;

    // radiance_row's rows at `depth`: rays[i] has travelled `travelled[i]` before its origin
    // (camera rays, `Primary`: none, and depth 0) and draws from paths[i]. shade's work, pass
    // by pass across the row.
    template <bool Primary>
        requires(!textured<Textures, Real> && std::is_same_v<LightSetT, LightSet<Real, PointLight>>)
    void shade_row(const Ray<Real>* rays, const Hit<Real>* hits, std::uint32_t found, int count, CameraPath* paths,
                   const Real* travelled, int depth, Vec3<Real>* radiance) const {
        if constexpr (Primary) depth = 0;
        const std::vector<PointLight<Real>>& lights = *lights_.template of_type<PointLight>();
        // What shade knows of a point before its direct lighting (the point made in place, the
        // rest of the record after it: value-initialised whole, the record had cost 5% of
        // simple_shading's instructions), and per light what that lighting draws.
        struct RowPoint {
            SurfacePoint<Real> point;
            Vec3<Real> normal, color;
            SpawnOrigins origins;
            std::uint32_t lit;  // bit k: light k's shadow ray is made
            bool front_face, inside_medium;
        };
        Unconstructed<RowPoint, row_width> points;
        std::array<std::array<Vec3<Real>, row_width>, row_lights> directions, radiances;
        std::array<std::array<Real, row_width>, row_lights> cosines;
        std::array<Unconstructed<Ray<Real>, row_width>, row_lights> shadows;  // per light, per ray
        // The lights' samples and shadow rays are made lane by lane, a point in each
        // (light_lanes), from the points gathered here.
        RowPoints row{};
        for (int i = 0; i < count; ++i) {
            CameraPath& path = paths[i];
            if (!((found >> i) & 1)) {
                radiance[i] = escaped(rays[i].direction, depth, path.pixel_uv);
                continue;
            }
            const Ray<Real>& ray = rays[i];
            RowPoint& at = points.make_from(std::size_t(i), [&] {
                return RowPoint{shading_surface<false>(geometry_, ray, hits[i], settings_.ray_offset)};
            });
            const Material<Real>& material = materials_[at.point.material];
            at.front_face = glm::dot(at.point.geometric_normal, ray.direction) < 0;
            at.normal = at.front_face ? at.point.shading_normal : -at.point.shading_normal;
            at.inside_medium = !at.front_face && material.type == scene::MaterialType::dielectric;
            if (at.inside_medium) continue;
            at.color = geometry_.emitted(hits[i].object) + material.ambient * ambient_light_;
            // direct_lighting's samples and shadow rays are made below, light by light across
            // the row (light_lanes); the stream steps past their draws now, in the same order.
            const Vec3<Real>& position = at.point.position;
            for (std::size_t k = 0; k < lights.size(); ++k) path.random.template skip<Real>(2);
            for (int axis = 0; axis < 3; ++axis) {
                row.position[axis][i] = position[axis];
                row.normal[axis][i] = at.normal[axis];
            }
            row.time[i] = at.point.time;
            row.shading |= std::uint32_t(1) << i;
        }
        if (row.shading != 0) {
            const auto origin_of = [&](std::size_t i, const Vec3<Real>& direction) {
                RowPoint& at = points[i];
                return leaving(at.point, at.normal, direction, at.point.time, at.origins).origin;
            };
            for (std::size_t k = 0; k < lights.size(); ++k) {
                const std::uint32_t lit =
                    light_lanes(lights[k], row, directions[k], radiances[k], cosines[k], shadows[k], origin_of);
                for (std::uint32_t rest = lit; rest != 0; rest &= rest - 1)
                    points[std::size_t(std::countr_zero(rest))].lit |= std::uint32_t(1) << k;
            }
        }
        // Each light's shadow rays across the row, side by side.
        std::array<std::uint32_t, row_width> blocked{};
        for (std::size_t k = 0; k < lights.size(); ++k) {
            Unconstructed<Ray<Real>, row_width> packed;
            std::array<int, row_width> owner;
            int n = 0;
            for (int i = 0; i < count; ++i) {
                if (!((found >> i) & 1) || !((points[std::size_t(i)].lit >> k) & 1)) continue;
                packed.make(std::size_t(n), shadows[k][std::size_t(i)]);
                owner[std::size_t(n++)] = i;
            }
            if (n == 0) continue;
            for (std::uint32_t hit = geometry_.occluded(RayBatch<Real>::all(packed.data(), n)); hit != 0; hit &= hit - 1)
                blocked[std::size_t(owner[std::size_t(std::countr_zero(hit))])] |= std::uint32_t(1) << k;
        }
        // Mirrors' and conductors' reflected rays, traced after the row's shading with their
        // closest hits found as one batch (as trace's own intersection finds
        // them below depth 0) and shaded as a row again, down to row_depth; each pixel draws
        // from its own stream, so its draws keep their order.
        Unconstructed<Ray<Real>, row_width> reflections;
        Unconstructed<CameraPath, row_width> reflection_paths;
        std::array<Vec3<Real>, row_width> weights;
        std::array<Real, row_width> reached;  // travelled to the reflection's origin
        std::array<int, row_width> reflecting;  // the ray's index in this row
        int reflected_count = 0;
        for (int i = 0; i < count; ++i) {
            if (!((found >> i) & 1)) continue;
            RowPoint& at = points[std::size_t(i)];
            const Material<Real>& material = materials_[at.point.material];
            if (!at.inside_medium) {
                Vec3<Real> direct(0);
                const Vec3<Real> to_viewer = -rays[i].direction;
                for (std::uint32_t lit = at.lit & ~blocked[std::size_t(i)]; lit != 0; lit &= lit - 1) {
                    const std::size_t k = std::size_t(std::countr_zero(lit));
                    LightSample<Real> sample;
                    sample.direction = directions[k][std::size_t(i)];
                    sample.radiance = radiances[k][std::size_t(i)];
                    direct += reflected(material, at.normal, to_viewer, sample, cosines[k][std::size_t(i)]);
                }
                at.color += direct;
            }
            CameraPath& path = paths[i];
            const Real travelled_here = (Primary ? Real(0) : travelled[i]) + hits[i].t;  // shade's travelled += hit.t
            if ((material.type == scene::MaterialType::mirror || material.type == scene::MaterialType::conductor) &&
                depth < settings_.max_recursion_depth) {
                // reflect_and_absorb's mirror and conductor, the trace deferred (no medium: only
                // dielectrics have one).
                const std::size_t j = std::size_t(reflected_count++);
                Real cos_incident;
                reflections.make(j, reflection_of(rays[i], at.point, material, at.normal, path, at.origins, cos_incident));
                reflection_paths.make(j, path);
                weights[j] = reflection_weight(material, cos_incident);
                reached[j] = travelled_here;
                reflecting[j] = i;
                radiance[i] = at.color;
                continue;
            }
            radiance[i] = reflect_and_absorb(rays[i], hits[i], at.point, material, at.normal, at.front_face,
                                             at.inside_medium, at.color, depth, path, travelled_here, at.origins);
        }
        if (reflected_count == 0) return;
        std::array<Hit<Real>, row_width> reflection_hits;
        const std::uint32_t met = geometry_.intersect(RayBatch<Real>::all(reflections.data(), reflected_count), reflection_hits.data());
        std::array<Vec3<Real>, row_width> traced;
        if (depth + 1 < row_depth) {
            shade_row<false>(reflections.data(), reflection_hits.data(), met, reflected_count, reflection_paths.data(),
                             reached.data(), depth + 1, traced.data());
        } else {
            for (int j = 0; j < reflected_count; ++j) {
                const Ray<Real>& reflection = reflections[std::size_t(j)];
                CameraPath& path = reflection_paths[std::size_t(j)];
                traced[std::size_t(j)] = ((met >> j) & 1) ? shade_apart(reflection, reflection_hits[std::size_t(j)],
                                                                        depth + 1, path, reached[std::size_t(j)])
                                                          : escaped(reflection.direction, depth + 1, path.pixel_uv);
            }
        }
        for (int j = 0; j < reflected_count; ++j)
            radiance[reflecting[std::size_t(j)]] += weights[std::size_t(j)] * traced[std::size_t(j)];
    }

    // The shading points of a row, SoA, for light_lanes: bit i of `shading` for point i.
    struct RowPoints {
        alignas(64) Real position[3][row_width];
        alignas(64) Real normal[3][row_width];
        Real time[row_width];
        std::uint32_t shading = 0;
    };

    // One point light's samples and shadow rays for the row's points, made as direct_lighting
    // makes them point by point (PointLight::sample, then make_shadow_ray), with each lane
    // computing the scalar code's operations in its order: the same directions, radiances,
    // cosines and rays, bit for bit. The lit lanes are those the scalar `cos <= 0` test lets
    // through (NaN included); returns them, whose rays are made. The square roots and
    // divisions of sixteen points then share vector instructions (hw2 mirror_room: 0.88 of
    // the wall time with the rays made point by point).
    // `origin_of(i, direction)`: point i's shadow-ray origin where rays leave by their error
    // bounds (leaving's, made lane by lane in the lit lanes' order); by the scene's epsilon the
    // origins are made here, lane by lane as leaving_ray makes them.
    template <class OriginOf>
    std::uint32_t light_lanes(const PointLight<Real>& light, const RowPoints& row, std::array<Vec3<Real>, row_width>& directions,
                              std::array<Vec3<Real>, row_width>& radiances, std::array<Real, row_width>& cosines,
                              Unconstructed<Ray<Real>, row_width>& shadows, OriginOf origin_of) const {
        constexpr int width = sizeof(Real) == 4 ? 16 : 8;
        static_assert(row_width % width == 0);
        using Lanes = simd::Pack<Real, width>;
        std::uint32_t lit = 0;
        for (int first = 0; first < row_width; first += width) {
            const std::uint32_t shading = (row.shading >> first) & ((std::uint32_t(1) << width) - 1);
            if (shading == 0) continue;
            Lanes p[3], n[3], to_light[3];
            for (int axis = 0; axis < 3; ++axis) {
                p[axis] = Lanes::load(row.position[axis] + first);
                n[axis] = Lanes::load(row.normal[axis] + first);
                to_light[axis] = Lanes::broadcast(light.position[axis]) - p[axis];
            }
            // PointLight::sample: glm's dot sums (x + y) + z.
            const Lanes distance_squared = (to_light[0] * to_light[0] + to_light[1] * to_light[1]) + to_light[2] * to_light[2];
            const Lanes distance = simd::sqrt(distance_squared);
            Lanes direction[3], radiance[3];
            for (int axis = 0; axis < 3; ++axis) {
                direction[axis] = to_light[axis] / distance;
                radiance[axis] = Lanes::broadcast(light.intensity[axis]) / distance_squared;
            }
            const Lanes cosine = (n[0] * direction[0] + n[1] * direction[1]) + n[2] * direction[2];
            const std::uint32_t lanes_lit = shading & (!(cosine <= Lanes::broadcast(Real(0)))).bits();
            // Rows 0-2 the directions, 3-5 the radiances, 6-8 the origins, 9-11 the shadow rays'
            // directions, 12 the cosines.
            alignas(64) Real stored[13][width];
            for (int axis = 0; axis < 3; ++axis) direction[axis].store(stored[axis]);
            Lanes origin[3], aim[3];
            if (settings_.ray_offset != RayOffset::error_bound) {
                // leaving_ray: the origin on the side dot(direction, normal) >= 0 names (the same
                // products as the cosine's, so the same sum).
                const auto towards = cosine >= Lanes::broadcast(Real(0));
                const Lanes epsilon = Lanes::broadcast(epsilon_);
                for (int axis = 0; axis < 3; ++axis) origin[axis] = p[axis] + select(towards, n[axis], -n[axis]) * epsilon;
            } else {
                alignas(64) Real origins[3][width] = {};
                for (std::uint32_t rest = lanes_lit; rest != 0; rest &= rest - 1) {
                    const int lane = std::countr_zero(rest);
                    const Vec3<Real> made =
                        origin_of(std::size_t(first + lane), Vec3<Real>(stored[0][lane], stored[1][lane], stored[2][lane]));
                    for (int axis = 0; axis < 3; ++axis) origins[axis][lane] = made[axis];
                }
                for (int axis = 0; axis < 3; ++axis) origin[axis] = Lanes::load(origins[axis]);
            }
            for (int axis = 0; axis < 3; ++axis) aim[axis] = (p[axis] + direction[axis] * distance) - origin[axis];
            // unit_vector: v * (1 / sqrt(dot(v, v))); a light at infinity keeps the sample's direction.
            const Lanes inverse_length =
                Lanes::broadcast(Real(1)) / simd::sqrt((aim[0] * aim[0] + aim[1] * aim[1]) + aim[2] * aim[2]);
            const auto finite = distance != Lanes::broadcast(infinity<Real>);
            for (int axis = 0; axis < 3; ++axis) {
                radiance[axis].store(stored[3 + axis]);
                origin[axis].store(stored[6 + axis]);
                select(finite, aim[axis] * inverse_length, direction[axis]).store(stored[9 + axis]);
            }
            cosine.store(stored[12]);
            alignas(64) Real distances[width];
            distance.store(distances);
            for (std::uint32_t rest = shading; rest != 0; rest &= rest - 1) {
                const int lane = std::countr_zero(rest);
                const std::size_t i = std::size_t(first + lane);
                directions[i] = Vec3<Real>(stored[0][lane], stored[1][lane], stored[2][lane]);
                radiances[i] = Vec3<Real>(stored[3][lane], stored[4][lane], stored[5][lane]);
                cosines[i] = stored[12][lane];
                if (!((lanes_lit >> lane) & 1)) continue;
                Ray<Real>& made = shadows.make(i);
                made.origin = Vec3<Real>(stored[6][lane], stored[7][lane], stored[8][lane]);
                made.direction = Vec3<Real>(stored[9][lane], stored[10][lane], stored[11][lane]);
                made.t_min = Real(0);
                made.t_max = distances[lane];
                made.time = row.time[i];
            }
            lit |= lanes_lit << first;
        }
        return lit;
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
    [[gnu::always_inline]] Vec3<Real> shade(const Ray<Real>& ray, const Hit<Real>& hit, int depth, CameraPath& path,
                                            Real travelled) const {
        SurfacePoint<Real> point = shading_surface(geometry_, textures_, ray, hit, settings_.ray_offset);
        // Textures change a copy; without them the material is read where it is stored.
        std::conditional_t<textured<Textures, Real>, Material<Real>, const Material<Real>&> material =
            materials_[point.material];
        travelled += hit.t;
        const RayCone<Real> cone{travelled * path.spread, std::abs(glm::dot(ray.direction, point.shading_normal))};
        if (const std::optional<Vec3<Real>> unshaded = textures_.apply(point, material, cone)) return *unshaded;
        Random& random = path.random;
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
            color += direct_lighting(point, normal, -d, material, random, origins);
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
    [[gnu::always_inline]] Vec3<Real> reflect_and_absorb(const Ray<Real>& ray, const Hit<Real>& hit,
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
    [[gnu::always_inline]] Ray<Real> reflection_of(const Ray<Real>& ray, const SurfacePoint<Real>& point,
                                                   const Material<Real>& material, const Vec3<Real>& normal,
                                                   CameraPath& path, SpawnOrigins& origins, Real& cos_incident) const {
        const Vec3<Real>& d = ray.direction;
        cos_incident = -glm::dot(d, normal);
        Vec3<Real> reflected = d + 2 * cos_incident * normal;
        if (material.roughness > 0) reflected = perturb(reflected, material.roughness, path.random.template uniform2<Real>());
        return stored_whole(leaving(point, normal, reflected, ray.time, origins));
    }

    // What a mirror's or a conductor's reflected radiance is multiplied by: its MirrorReflectance,
    // times the conductor's Fresnel reflectance (fresnel * mirror, then the radiance: the
    // products in the order the expression always took them).
    [[gnu::always_inline]] Vec3<Real> reflection_weight(const Material<Real>& material, Real cos_incident) const {
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
    [[gnu::always_inline]] Ray<Real> leaving(const SurfacePoint<Real>& point, const Vec3<Real>& normal,
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
                               const Material<Real>& material, Random& random, SpawnOrigins& origins) const {
        if constexpr (std::is_same_v<LightSetT, LightSet<Real, PointLight>>) {
            const std::vector<PointLight<Real>>& lights = *lights_.template of_type<PointLight>();
            if (lights.size() > 1)
                return point_lighting_batched(point, normal, to_viewer, material, random, origins, lights);
        }
        Vec3<Real> color(0);
        lights_.for_each([&](const auto& light) { light_term(light, point, normal, to_viewer, material, random, origins, color); });
        return color;
    }

    // One light's term of direct_lighting's sum, added to `color` where its shadow ray is not
    // blocked.
    template <class L>
    [[gnu::always_inline]] void light_term(const L& light, const SurfacePoint<Real>& point, const Vec3<Real>& normal,
                                           const Vec3<Real>& to_viewer, const Material<Real>& material, Random& random,
                                           SpawnOrigins& origins, Vec3<Real>& color) const {
        const Vec3<Real>& position = point.position;
        // A light that takes no sample (point, directional, spot: sample(at) alone) gets none
        // drawn, but the stream steps past its two numbers, so that every later draw is the
        // one it was (the images stay the same).
        const ShadingFrame<Real> at{position, normal};
        const LightSample<Real> sample = [&] {
            if constexpr (draws_nothing<L>) {
                random.template skip<Real>(2);
                return light.sample(at);
            } else {
                return light.sample(at, random.uniform2<Real>());
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
                                                        Random& random, SpawnOrigins& origins, const PointLights& lights) const {
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
                random.template skip<Real>(2);
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
    [[gnu::always_inline]] void make_shadow_ray(Ray<Real>& made, const SurfacePoint<Real>& point, const Vec3<Real>& normal,
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
    [[gnu::always_inline]] Vec3<Real> reflected(const Material<Real>& material, const Vec3<Real>& normal,
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
        Random& random = path.random;
        if (material.roughness > 0) transmitted = perturb(transmitted, material.roughness, random.uniform2<Real>());
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
    template <Scalar Real, class Geometry, class LightSetT, class Textures, class Environment>
    using Type = WhittedIntegrator<Real, Geometry, LightSetT, Textures, Environment>;

    // Not scenes with a path-traced camera: those need the PathTracer policy.
    static constexpr bool covers(const scene::Needs& needs) { return !needs.path_tracing; }
};

}  // namespace prism
