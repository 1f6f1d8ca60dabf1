// WhittedIntegrator's work on several camera rays at once, without changing a bit of what each
// ray gets alone: a row's pixels (shade_row, for point-lit renderers without textures: every
// hit's shadow rays made first, each light's tested as one batch across the row, mirrors'
// reflections traced as rows of their own) and a pixel's samples (radiances_at: the lights that
// draw nothing sampled for every sample first, their shadow rays tested as one batch per light).
// Included by whitted_integrator.hpp, after the class: these are its members' definitions.
#pragma once

#include <prism/render/whitted_integrator.hpp>

namespace prism {

template <Scalar Real, class Geometry, class LightSetT, class Textures, class Environment, class Sampler>
template <class StartSample>
void WhittedIntegrator<Real, Geometry, LightSetT, Textures, Environment, Sampler>::radiances_at(const Ray<Real>* rays, const Hit<Real>* hits, std::uint32_t found, int count,
                                                                                  CameraPath& path, StartSample start_sample,
                                                                                  Vec3<Real>* radiance) const {
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
        if (textures_.apply(at.point, material_of(i), radiance[i], cone)) continue;
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
        if constexpr (sampled_without_draws<std::decay_t<decltype(light)>, Real>) {
            if (k == prelit_lights || lighting == 0) return;
            const std::size_t j = k++;
            Unconstructed<Ray<Real>, prelit_width> shadows;
            std::array<int, prelit_width> owner;
            int n = 0;
            if constexpr (std::is_same_v<std::decay_t<decltype(light)>, PointLight<Real>>) {
                // Point lights lane by lane, as shade_row makes them (point_light_lanes).
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
                    point_light_lanes(light, *row, scene_epsilon(), directions[j], radiances[j], cosines[j], made, origin_of);
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
    // Each sample shaded in its turn, as shade shades it, from its own start in the sampler (the
    // samples above drew nothing).
    for (std::uint32_t rest = shading; rest != 0; rest &= rest - 1) {
        const int i = std::countr_zero(rest);
        start_sample(i);
        PrelitPoint& at = points[std::size_t(i)];
        const Material<Real>& material = material_of(i);
        Vec3<Real> color(0);
        if (!at.inside_medium) {
            color = geometry_.emitted(hits[i].object) + material.ambient * ambient_light_;
            const Vec3<Real> to_viewer = -rays[i].direction;
            Vec3<Real> direct(0);
            std::size_t light_index = 0;  // among the prelit lights
            lights_.for_each([&](const auto& light) {
                if constexpr (sampled_without_draws<std::decay_t<decltype(light)>, Real>) {
                    if (light_index < prelit_lights) {
                        const std::size_t j = light_index++;
                        path.sampler.template skip<Real>(2);
                        if (!((at.visible >> j) & 1)) return;
                        LightSample<Real> sample;
                        sample.direction = directions[j][std::size_t(i)];
                        sample.radiance = radiances[j][std::size_t(i)];
                        direct += reflected(material, at.normal, to_viewer, sample, cosines[j][std::size_t(i)]);
                        return;
                    }
                }
                light_term(light, at.point, at.normal, to_viewer, material, path.sampler, at.origins, direct);
            });
            color += direct;
        }
        radiance[i] = reflect_and_absorb(rays[i], hits[i], at.point, material, at.normal, at.front_face,
                                         at.inside_medium, color, 0, path, at.travelled, at.origins);
    }
}

// radiance_row's rows at `depth`: rays[i] has travelled `travelled[i]` before its origin
// (camera rays: `travelled` null, none, and depth 0) and draws from paths[i]. shade's work, pass
// by pass across the row.
template <Scalar Real, class Geometry, class LightSetT, class Textures, class Environment, class Sampler>
void WhittedIntegrator<Real, Geometry, LightSetT, Textures, Environment, Sampler>::shade_row(const Ray<Real>* rays, const Hit<Real>* hits, std::uint32_t found, int count,
                                                                               CameraPath* paths, const Real* travelled, int depth,
                                                                               Vec3<Real>* radiance) const {
    const std::vector<PointLight<Real>>& lights = *lights_.template of_type<PointLight>();
    // What shade knows of a point before its direct lighting (the point made in place, the
    // rest of the record after it: value-initialised whole, the record had cost 5% of
    // simple_shading's instructions), and per light what that lighting draws.
    struct RowPoint {
        SurfacePoint<Real> point;
        Vec3<Real> normal{0}, color{0};
        SpawnOrigins origins{};
        std::uint32_t lit = 0;  // bit k: light k's shadow ray is made
        bool front_face = false, inside_medium = false;
    };
    Unconstructed<RowPoint, row_width> points;
    std::array<std::array<Vec3<Real>, row_width>, row_lights> directions, radiances;
    std::array<std::array<Real, row_width>, row_lights> cosines;
    std::array<Unconstructed<Ray<Real>, row_width>, row_lights> shadows;  // per light, per ray
    // The lights' samples and shadow rays are made lane by lane, a point in each
    // (point_light_lanes), from the points gathered here.
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
        // the row (point_light_lanes); the stream steps past their draws now, in the same order.
        const Vec3<Real>& position = at.point.position;
        for (std::size_t k = 0; k < lights.size(); ++k) path.sampler.template skip<Real>(2);
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
                point_light_lanes(lights[k], row, scene_epsilon(), directions[k], radiances[k], cosines[k], shadows[k], origin_of);
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
        const Real travelled_here = (travelled ? travelled[i] : Real(0)) + hits[i].t;  // shade's travelled += hit.t
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
        shade_row(reflections.data(), reflection_hits.data(), met, reflected_count, reflection_paths.data(), reached.data(),
                  depth + 1, traced.data());
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

}  // namespace prism
