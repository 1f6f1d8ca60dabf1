// Path tracing (Kajiya 1986), as the course's <Renderer>PathTracing</Renderer> asks for it, with
// the <RendererParams> each camera lists:
// - ImportanceSampling: directions drawn from the material's BRDF (material/brdf.hpp: its
//   specular lobe or the cosine-weighted hemisphere) rather than uniformly over the hemisphere;
// - NextEventEstimation: every light sampled at every non-specular vertex (Whitted-style shadow
//   rays), and emission that a BRDF-sampled ray then finds not counted again;
// - RussianRoulette: a path continues with probability q = min(1, max throughput) and its
//   throughput is divided by q: unbiased (Arvo and Kirk 1990; pbrt-v4 sec. 14.5.3);
// - MultipleImportanceSampling (prism's own word, beyond the course): object lights reached by
//   next-event and by BRDF samples are weighed by the power heuristic (Veach and Guibas 1995;
//   Veach's thesis sec. 9.2), so neither small bright lights nor glossy surfaces are noisy.
// A path has at most MaxRecursionDepth bounces after the camera's hit, whatever the parameters,
// so every combination estimates the same image (Russian roulette only thins paths within that
// bound). Mirrors, conductors and dielectrics scatter as in the course's ray tracer, choosing
// reflection or refraction by the Fresnel weight, and keep the BRDF terms it shades them with.
// The loop is iterative: the path's length is bounded by the depth, never by native recursion.
// Cameras without <Renderer>PathTracing</Renderer> in the same scene render with the course's
// ray tracer, which this integrator holds.
#pragma once

#include <prism/geometry/backface_culling.hpp>
#include <prism/light/environment_light.hpp>
#include <prism/light/light_mesh.hpp>
#include <prism/light/light_sphere.hpp>
#include <prism/material/brdf.hpp>
#include <prism/memory/unconstructed.hpp>
#include <prism/render/whitted_integrator.hpp>
#include <prism/sampling/hemisphere.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <vector>

namespace prism {

namespace path_tracing {

// Veach's power heuristic with exponent 2, for one sample of each strategy.
template <Scalar Real>
Real power_heuristic(Real chosen, Real other) {
    const Real a = chosen * chosen, b = other * other;
    return a + b > 0 ? a / (a + b) : Real(0);
}

}  // namespace path_tracing

template <Scalar Real, class Geometry, class LightSetT, class Textures = NoTextures<Real>,
          class Environment = NoEnvironment<Real>, class Sampler = IndependentSampler>
class PathTracerIntegrator {
public:
    using RayTracer = WhittedIntegrator<Real, Geometry, LightSetT, Textures, Environment, Sampler>;

    PathTracerIntegrator(const Geometry& geometry, const LightSetT& lights, const std::vector<Material<Real>>& materials,
                         const Textures& textures, const Environment& environment, const Vec3<Real>& ambient_light,
                         const Vec3<Real>& background, const IntegratorSettings& settings)
        : whitted_(geometry, lights, materials, textures, environment, ambient_light, background, settings),
          geometry_(geometry), lights_(lights), materials_(materials), textures_(textures), environment_(environment),
          background_(background), settings_(settings), epsilon_(Real(settings.shadow_ray_epsilon)),
          bounce_dimensions_(dimension::lights + 2 * int(lights.size())) {
        // Which object light each emitting object is, for the density of reaching it by
        // next-event estimation (multiple importance sampling).
        emitters_.assign(geometry.instance_count(), Emitter{});
        if (const auto* meshes = lights.template of_type<LightMesh>())
            for (std::size_t i = 0; i < meshes->size(); ++i)
                if ((*meshes)[i].object < emitters_.size()) emitters_[(*meshes)[i].object] = {Emitter::mesh, std::uint32_t(i)};
        if (const auto* spheres = lights.template of_type<LightSphere>())
            for (std::size_t i = 0; i < spheres->size(); ++i)
                if ((*spheres)[i].object < emitters_.size())
                    emitters_[(*spheres)[i].object] = {Emitter::sphere, std::uint32_t(i)};
    }

    struct CameraPath {
        Sampler& sampler;
        Vec2<Real> pixel_uv;
        Real spread = 0;
        scene::RendererParams renderer{};  // the camera's; without path_tracing, the ray tracer renders
    };

    Vec3<Real> radiance(const Ray<Real>& ray, CameraPath& path) const {
        if (!path.renderer.path_tracing) {
            typename RayTracer::CameraPath traced = ray_traced(path);
            return whitted_.radiance(ray, traced);
        }
        return trace(ray, path, nullptr, false);
    }

    // Camera rays several at a time, as the ray tracer takes them (WhittedIntegrator: their
    // closest hits first, then each ray's radiance from its hit), for the cameras of both
    // integrators. A path's camera hit is the one its own first intersection finds (the same
    // culling rule; a batch's hits are each ray's own), and the path goes on from it with
    // the same draws: the same bits. Without these, a path-traced scene's ray-traced cameras
    // lost the ray tracer's batches (hw7 VeachAjar's first camera).
    // The Renderer batches only the ray-traced cameras: a path-traced camera's rays one by one. Its
    // samples' camera rays as one batch through the index made hw7
    // path_diffuse and path_glass 1.02-1.04 times slower (their index has 3 leaves; paired, 5
    // rounds), while VeachAjar's ray-traced camera gains the ray tracer's rows and prelit lights.
    bool batches_camera_rays(const scene::Camera& camera) const {
        return !camera.renderer.path_tracing && whitted_.batches_camera_rays(camera);
    }
    std::uint32_t camera_hits(Ray<Real>* rays, Hit<Real>* hits, int count) const {
        return whitted_.camera_hits(rays, hits, count);
    }
    Vec3<Real> radiance_at(const Ray<Real>& ray, const Hit<Real>& hit, bool found, CameraPath& path) const {
        if (!path.renderer.path_tracing) {
            typename RayTracer::CameraPath traced = ray_traced(path);
            return whitted_.radiance_at(ray, hit, found, traced);
        }
        return trace(ray, path, &hit, found);
    }
    // A row's pixels of one sample from their camera hits, one after another (the ray tracer's
    // rows shade point lights alone, and this renderer holds every light type).
    static constexpr int row_width = RayTracer::row_width;
    template <class MakePath>
    void radiance_row(const Ray<Real>* rays, const Hit<Real>* hits, std::uint32_t found, int count, MakePath make_path,
                      Vec3<Real>* radiance) const {
        for (int i = 0; i < count; ++i) {
            CameraPath path = make_path(i);
            radiance[i] = radiance_at(rays[i], hits[i], (found >> i) & 1, path);
        }
    }
    // A pixel's samples from their camera hits: the ray tracer's side-by-side shadow rays for a
    // ray-traced camera; a path-traced camera's paths one after another, each from its hit.
    static constexpr int prelit_width = RayTracer::prelit_width;
    bool prelights() const { return whitted_.prelights(); }
    template <class StartSample>
    void radiances_at(const Ray<Real>* rays, const Hit<Real>* hits, std::uint32_t found, int count, CameraPath& path,
                      StartSample start_sample, Vec3<Real>* radiance) const {
        if (!path.renderer.path_tracing) {
            typename RayTracer::CameraPath traced = ray_traced(path);
            whitted_.radiances_at(rays, hits, found, count, traced, start_sample, radiance);
            return;
        }
        for (int i = 0; i < count; ++i) {
            start_sample(i);
            radiance[i] = trace(rays[i], path, &hits[i], (found >> i) & 1);
        }
    }

private:
    // Where a bounce's draws sit in its block of the sampler's dimensions: the same uses at the
    // same dimensions in every sample, whichever branches earlier bounces took, so each use is
    // stratified across the pixel's samples by the sampler (a stream ignores the seeks). The
    // direction's pair serves the BRDF's sample and the rough specular reflection, of which a
    // bounce takes one; each light of next-event estimation has its pair after the rest.
    struct dimension {
        static constexpr int specular_choice = 0, direction = 1, fresnel_choice = 3, transmitted = 4, roulette = 6,
                             lights = 7;
    };

    struct Emitter {
        enum Type : std::uint8_t { none, mesh, sphere } type = none;
        std::uint32_t index = 0;
    };

    static typename RayTracer::CameraPath ray_traced(CameraPath& path) {
        return {path.sampler, path.pixel_uv, path.spread};
    }

    // The path from a camera ray; `camera_hit` (with `camera_found`): its closest hit, found
    // already (camera_hits), or null to find it here.
    Vec3<Real> trace(Ray<Real> ray, CameraPath& path, const Hit<Real>* camera_hit, bool camera_found) const {
        const scene::RendererParams& params = path.renderer;
        Sampler& sampler = path.sampler;
        // Each bounce draws from its own block of the sampler's dimensions (`dimension`), after
        // those the camera sample took.
        const int first_dimension = sampler.dimension();
        Vec3<Real> color(0), throughput(1);
        // Whether emission found by this ray counts in full: at the camera, after a specular
        // bounce, or without next-event estimation. Otherwise it was already counted by the
        // light sample at the previous vertex (or is weighed against it, with MIS).
        bool count_emission = true;
        Real scatter_pdf = 0;        // the solid-angle density of the last BRDF-sampled direction
        ShadingFrame<Real> previous;  // the last vertex, as next-event estimation saw it
        Real travelled = 0;
        for (int depth = 0;; ++depth) {
            Hit<Real> hit;
            bool found;
            if (depth == 0 && camera_hit) {
                found = camera_found;
                if (found) hit = *camera_hit;
            } else {
                found = intersect(ray, depth, hit);
            }
            if (!found) {
                color += throughput * escaped(ray.direction, depth, count_emission, path.pixel_uv);
                break;
            }
            SurfacePoint<Real> point = shading_surface(geometry_, textures_, ray, hit, settings_.ray_offset);
            travelled += hit.t;
            // Textures change a copy of the material; a point without textures reads it where it
            // is stored (a copy a vertex was 7% of trace's own samples on path_diffuse).
            const Material<Real>* stored = &materials_[point.material];
            Unconstructed<Material<Real>, 1> textured_material;  // (a std::optional's flag: 18 instructions a vertex)
            if (!point.textures.empty()) {
                const RayCone<Real> cone{travelled * path.spread,
                                         std::abs(glm::dot(ray.direction, point.shading_normal))};
                stored = &textured_material.make(0, *stored);
                if (Vec3<Real> unshaded; textures_.apply(point, textured_material[0], unshaded, cone)) {
                    color += throughput * unshaded;
                    break;
                }
            }
            const Material<Real>& material = *stored;
            const Vec3<Real>& d = ray.direction;
            const bool front_face = glm::dot(point.geometric_normal, d) < 0;
            const Vec3<Real> normal = front_face ? point.shading_normal : -point.shading_normal;

            const Vec3<Real> emitted = geometry_.emitted(hit.object);
            if (emitted != Vec3<Real>(0)) {
                if (count_emission) color += throughput * emitted;
                else if (params.multiple_importance)
                    color += throughput * emitted *
                             path_tracing::power_heuristic(scatter_pdf,
                                                           light_pdf(hit, previous, point));
            }
            if (depth >= settings_.max_recursion_depth) break;

            // Beer's law for a path that crossed a dielectric's inside to reach this point.
            if (!front_face && material.type == scene::MaterialType::dielectric)
                throughput *= glm::exp(-material.absorption_coefficient * hit.t);

            Vec3<Real> direction;
            // The course's ray tracer shades a mirror, conductor or dielectric with its BRDF (or
            // Blinn-Phong) terms and adds what it reflects and refracts; so does prism's
            // (WhittedIntegrator::trace). Here the path continues along one of the two, the
            // specular one with probability `specular_share`, each divided by its probability;
            // next-event estimation covers the BRDF terms whichever is taken.
            const bool specular = material.type != scene::MaterialType::blinn_phong;
            const Real specular_share = specular ? specular_choice(material, front_face) : Real(0);
            const int block = first_dimension + depth * bounce_dimensions_;
            if (params.next_event_estimation && specular_share < 1)
                color += throughput *
                         direct_lighting(point, normal, -d, material, params, sampler, block, 1 - specular_share);
            sampler.seek(block + dimension::specular_choice);
            if (specular_share > 0 && (specular_share >= 1 || sampler.template uniform<Real>() < specular_share)) {
                direction = specular_direction(d, normal, front_face, material, sampler, block, throughput);
                throughput /= specular_share;
                count_emission = true;
            } else {
                const Vec3<Real> wo = -d;
                Real density;
                Vec3<Real> value;
                sampler.seek(block + dimension::direction);
                if (params.importance_sampling) {
                    const BrdfSample<Real> sample = sample_brdf(material, normal, wo, sampler.template uniform2<Real>());
                    direction = sample.direction;
                    density = sample.pdf;
                    value = sample.value;
                } else {
                    direction = sample_uniform_hemisphere(normal, sampler.template uniform2<Real>());
                    density = 1 / (2 * pi<Real>);
                    value = evaluate_brdf(material, normal, direction, wo);
                }
                const Real cos_theta = glm::dot(normal, direction);
                if (!(density > 0) || !(cos_theta > 0)) break;
                density *= 1 - specular_share;  // the chance of taking the BRDF at all
                throughput *= value * (cos_theta / density);
                scatter_pdf = density;
                count_emission = !params.next_event_estimation;
            }
            if (throughput == Vec3<Real>(0)) break;
            if (params.russian_roulette && depth > 0) {
                const Real survival = std::min(Real(1), std::max({throughput.x, throughput.y, throughput.z}));
                sampler.seek(block + dimension::roulette);
                if (sampler.template uniform<Real>() >= survival) break;
                throughput /= survival;
            }
            previous = {point.position, normal};
            // In one store (stored_whole): the next intersect reads the ray whole.
            ray = stored_whole(leaving(point, normal, direction, ray.time));
        }
        return color;
    }

    bool intersect(Ray<Real>& ray, int depth, Hit<Real>& hit) const {
        return closest_hit(geometry_, ray, hit, culling_at_depth(settings_.backface_culling, depth));
    }

    // Mirrors and conductors reflect; dielectrics reflect or refract, chosen by the Fresnel
    // weight so that the throughput keeps its magnitude (the choice's probability cancels it).
    Vec3<Real> specular_direction(const Vec3<Real>& d, const Vec3<Real>& normal, bool front_face,
                                  const Material<Real>& material, Sampler& sampler, int block,
                                  Vec3<Real>& throughput) const {
        using scene::MaterialType;
        const Real cos_incident = -glm::dot(d, normal);
        Vec3<Real> reflected = d + 2 * cos_incident * normal;
        sampler.seek(block + dimension::direction);
        if (material.roughness > 0) reflected = perturb(reflected, material.roughness, sampler.template uniform2<Real>());
        if (material.type == MaterialType::mirror) {
            throughput *= material.mirror;
            return reflected;
        }
        if (material.type == MaterialType::conductor) {
            throughput *= material.mirror * fresnel_conductor(std::max(cos_incident, Real(0)), material.refraction_index,
                                                              material.absorption_index);
            return reflected;
        }
        const Real n1 = front_face ? Real(1) : material.refraction_index;
        const Real n2 = front_face ? material.refraction_index : Real(1);
        const Real ratio = n1 / n2;
        const Real sin2_transmitted = ratio * ratio * (1 - cos_incident * cos_incident);
        if (sin2_transmitted >= 1) return reflected;
        const Real cos_transmitted = std::sqrt(1 - sin2_transmitted);
        const Real fresnel = fresnel_dielectric(cos_incident, cos_transmitted, n1, n2);
        sampler.seek(block + dimension::fresnel_choice);
        if (sampler.template uniform<Real>() < fresnel) return reflected;
        Vec3<Real> transmitted = unit_vector(ratio * d + (ratio * cos_incident - cos_transmitted) * normal);
        sampler.seek(block + dimension::transmitted);
        if (material.roughness > 0) transmitted = perturb(transmitted, material.roughness, sampler.template uniform2<Real>());
        if (material.transparency != Vec3<Real>(0)) throughput *= material.transparency;
        return transmitted;
    }

    // The probability of continuing a path along the specular reflection or refraction of a
    // mirror, conductor or dielectric rather than its BRDF terms: 1 without such terms (and from
    // inside a dielectric, which the course does not shade), otherwise in proportion to the
    // largest specular weight against the largest BRDF weight.
    static Real specular_choice(const Material<Real>& material, bool front_face) {
        using scene::MaterialType;
        if (!front_face && material.type == MaterialType::dielectric) return 1;
        const Real shaded = std::max({material.diffuse.x, material.diffuse.y, material.diffuse.z}) +
                            std::max({material.specular.x, material.specular.y, material.specular.z});
        if (!(shaded > 0)) return 1;
        const Real reflected = material.type == MaterialType::dielectric
                                   ? Real(1)
                                   : std::max({material.mirror.x, material.mirror.y, material.mirror.z});
        if (!(reflected > 0)) return 0;
        return std::clamp(reflected / (reflected + shaded), Real(0.1), Real(0.9));
    }

    // Next-event estimation: one sample of every light, as the course's ray tracer takes them.
    // `brdf_share`: the probability that the path continues by sampling the BRDF here, which
    // scales that strategy's density in the MIS weight.
    Vec3<Real> direct_lighting(const SurfacePoint<Real>& point, const Vec3<Real>& normal, const Vec3<Real>& wo,
                               const Material<Real>& material, const scene::RendererParams& params,
                               Sampler& sampler, int block, Real brdf_share) const {
        Vec3<Real> color(0);
        int light_dimension = block + dimension::lights;
        lights_.for_each([&](const auto& light) {
            sampler.seek(light_dimension);
            light_dimension += 2;
            const ShadingFrame<Real> at{point.position, normal};
            const LightSample<Real> sample = [&] {
                if constexpr (sampled_without_draws<std::decay_t<decltype(light)>, Real>) {
                    sampler.template skip<Real>(2);
                    return light.sample(at);
                } else {
                    return light.sample(at, sampler.template uniform2<Real>());
                }
            }();
            const Real cos_light = glm::dot(normal, sample.direction);
            if (cos_light <= 0 || sample.radiance == Vec3<Real>(0)) return;
            Ray<Real> shadow = leaving(point, normal, sample.direction, point.time);
            if (!std::isinf(sample.distance)) {
                const Vec3<Real> target = point.position + sample.direction * sample.distance;
                shadow.direction = unit_vector(target - shadow.origin);
                // An object light's own surface is at the far end: stop short of it.
                shadow.t_max = glm::length(target - shadow.origin) * (1 - Real(1e-4));
            }
            if (blocked(geometry_, shadow)) return;
            Vec3<Real> contribution = evaluate_brdf(material, normal, sample.direction, wo) * cos_light * sample.radiance;
            if (params.multiple_importance && sample.pdf > 0)
                contribution *= path_tracing::power_heuristic(
                    sample.pdf, brdf_share * scatter_density(params, material, normal, sample.direction, wo));
            color += contribution;
        });
        return color;
    }

    // The solid-angle density with which the path's next direction is drawn: from the BRDF with
    // ImportanceSampling, uniformly over the hemisphere without.
    static Real scatter_density(const scene::RendererParams& params, const Material<Real>& material,
                                const Vec3<Real>& normal, const Vec3<Real>& wi, const Vec3<Real>& wo) {
        if (params.importance_sampling) return brdf_pdf(material, normal, wi, wo);
        return glm::dot(normal, wi) > 0 ? 1 / (2 * pi<Real>) : Real(0);
    }

    // The density next-event estimation at `from` gives to reaching `point`, found by `hit`.
    Real light_pdf(const Hit<Real>& hit, const ShadingFrame<Real>& from, const SurfacePoint<Real>& point) const {
        if (hit.object >= emitters_.size()) return 0;
        const Emitter& emitter = emitters_[hit.object];
        if (const auto* meshes = lights_.template of_type<LightMesh>(); meshes && emitter.type == Emitter::mesh)
            return (*meshes)[emitter.index].pdf(from, point.position, point.geometric_normal,
                                                geometry_.emitting_triangle(hit));
        if (const auto* spheres = lights_.template of_type<LightSphere>(); spheres && emitter.type == Emitter::sphere)
            return (*spheres)[emitter.index].pdf(from.position, point.position, point.geometric_normal);
        return 0;
    }

    // A ray that meets nothing: the background at the camera; the environment after a specular
    // bounce or without next-event estimation (which otherwise samples it).
    Vec3<Real> escaped(const Vec3<Real>& direction, int depth, bool count_emission, const Vec2<Real>& pixel_uv) const {
        if (depth == 0) {
            if (const std::optional<Vec3<Real>> texture = textures_.background(pixel_uv)) return *texture;
            return environment_.present() ? environment_.radiance(direction) : background_;
        }
        return environment_.present() && count_emission ? environment_.radiance(direction) : Vec3<Real>(0);
    }

    Ray<Real> leaving(const SurfacePoint<Real>& point, const Vec3<Real>& normal, const Vec3<Real>& direction,
                      Real time) const {
        return leaving_ray(geometry_, settings_.ray_offset, epsilon_, point, normal, direction, time);
    }

    RayTracer whitted_;
    const Geometry& geometry_;
    const LightSetT& lights_;
    const std::vector<Material<Real>>& materials_;
    const Textures& textures_;
    const Environment& environment_;
    Vec3<Real> background_;
    IntegratorSettings settings_;
    Real epsilon_;
    int bounce_dimensions_;          // the sampler's dimensions a bounce takes (`dimension`)
    std::vector<Emitter> emitters_;  // per object of the geometry
};

// The Config policy that path traces the cameras asking for it (and ray traces the others).
struct PathTracer {
    template <Scalar Real, class Geometry, class LightSetT, class Textures, class Environment, class Sampler>
    using Type = PathTracerIntegrator<Real, Geometry, LightSetT, Textures, Environment, Sampler>;

    static constexpr bool covers(const scene::Needs&) { return true; }
};

}  // namespace prism
