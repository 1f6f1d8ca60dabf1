// Recursive ray tracing as the course defines it (Whitted 1980 with Blinn-Phong shading):
// ambient + per-light diffuse and specular with shadow rays; mirror and conductor reflection
// (conductors weighted by their Fresnel reflectance); dielectric reflection and refraction with
// Fresnel weights, total internal reflection, and Beer's law attenuation inside the medium.
#pragma once

#include <prism/geometry/hit.hpp>
#include <prism/material/fresnel.hpp>
#include <prism/material/material.hpp>

#include <cmath>
#include <vector>

namespace prism {

struct IntegratorSettings {
    int max_recursion_depth = 0;
    double shadow_ray_epsilon = 1e-3;  // offset along the normal for every secondary ray
    bool cull_backfaces = false;       // for primary rays; secondary rays must see back faces
};

template <Scalar Real, class Geometry, class LightSetT>
class WhittedIntegrator {
public:
    WhittedIntegrator(const Geometry& geometry, const LightSetT& lights, const std::vector<Material<Real>>& materials,
                      const Vec3<Real>& ambient_light, const Vec3<Real>& background, const IntegratorSettings& settings)
        : geometry_(geometry), lights_(lights), materials_(materials), ambient_light_(ambient_light),
          background_(background), settings_(settings), epsilon_(Real(settings.shadow_ray_epsilon)) {}

    // Radiance arriving along a ray with a unit direction.
    Vec3<Real> radiance(Ray<Real> ray, int depth) const {
        Hit<Real> hit;
        const bool found = (depth == 0 && settings_.cull_backfaces) ? geometry_.template intersect<true>(ray, hit)
                                                                    : geometry_.template intersect<false>(ray, hit);
        // The course shows the background only where primary rays escape; a secondary ray
        // that escapes brings back nothing.
        if (!found) return depth == 0 ? background_ : Vec3<Real>(0);

        const SurfacePoint<Real> point = geometry_.surface(ray, hit);
        const Material<Real>& material = materials_[point.material];
        const Vec3<Real>& d = ray.direction;
        const bool front_face = glm::dot(point.geometric_normal, d) < 0;
        // Shading uses the normal on the side the ray arrives from.
        const Vec3<Real> normal = front_face ? point.shading_normal : -point.shading_normal;

        // A ray travelling inside a dielectric sees the interface from within, where no light
        // reaches directly: the course shades only the outside (scienceTree_glass: 30.5 dB
        // with inside shading, 58.5 dB without).
        const bool inside_medium = !front_face && material.type == scene::MaterialType::dielectric;
        Vec3<Real> color(0);
        if (!inside_medium) {
            color = material.ambient * ambient_light_;
            color += direct_lighting(point.position, normal, -d, material);
        }

        // Blinn-Phong surfaces spawn no rays; the others reflect (and dielectrics refract).
        if (depth < settings_.max_recursion_depth && material.type != scene::MaterialType::blinn_phong) {
            using scene::MaterialType;
            const Real cos_incident = -glm::dot(d, normal);
            const Vec3<Real> reflected = d + 2 * cos_incident * normal;
            const Ray<Real> reflection{point.position + normal * epsilon_, reflected};
            switch (material.type) {
                case MaterialType::blinn_phong: break;
                case MaterialType::mirror: color += material.mirror * radiance(reflection, depth + 1); break;
                case MaterialType::conductor: {
                    const Real fresnel = fresnel_conductor(std::max(cos_incident, Real(0)), material.refraction_index,
                                                           material.absorption_index);
                    color += fresnel * material.mirror * radiance(reflection, depth + 1);
                    break;
                }
                case MaterialType::dielectric:
                    color += dielectric(point.position, d, normal, cos_incident, front_face, material, reflection, depth);
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

private:
    Vec3<Real> direct_lighting(const Vec3<Real>& position, const Vec3<Real>& normal, const Vec3<Real>& to_viewer,
                               const Material<Real>& material) const {
        Vec3<Real> color(0);
        const Vec3<Real> shadow_origin = position + normal * epsilon_;
        lights_.for_each([&](const auto& light) {
            const LightSample<Real> sample = light.sample({position, normal});
            const Real cos_light = glm::dot(normal, sample.direction);
            if (cos_light <= 0) return;
            // The shadow ray leaves the offset origin aimed at the light, and anything nearer than
            // the light's distance from the shading point blocks it. So a surface through the
            // light itself blocks it for every point, not by rounding (mirror_room's ceiling
            // holds a light: 20.3 dB with a per-pixel coin flip, 64.5 dB consistent).
            const Vec3<Real> shadow_direction =
                std::isinf(sample.distance)
                    ? sample.direction
                    : glm::normalize(position + sample.direction * sample.distance - shadow_origin);
            const Ray<Real> shadow{shadow_origin, shadow_direction, Real(0), sample.distance};
            if (geometry_.occluded(shadow)) return;
            const Vec3<Real> half_vector = glm::normalize(sample.direction + to_viewer);
            const Real cos_half = std::max(glm::dot(normal, half_vector), Real(0));
            color += (material.diffuse * cos_light + material.specular * std::pow(cos_half, material.phong_exponent)) *
                     sample.radiance;
        });
        return color;
    }

    Vec3<Real> dielectric(const Vec3<Real>& position, const Vec3<Real>& d, const Vec3<Real>& normal, Real cos_incident,
                          bool front_face, const Material<Real>& material, const Ray<Real>& reflection,
                          int depth) const {
        const Real n1 = front_face ? Real(1) : material.refraction_index;
        const Real n2 = front_face ? material.refraction_index : Real(1);
        const Real ratio = n1 / n2;
        const Real sin2_transmitted = ratio * ratio * (1 - cos_incident * cos_incident);
        if (sin2_transmitted >= 1) return radiance(reflection, depth + 1);  // total internal reflection
        const Real cos_transmitted = std::sqrt(1 - sin2_transmitted);
        const Real fresnel = fresnel_dielectric(cos_incident, cos_transmitted, n1, n2);
        const Vec3<Real> transmitted = glm::normalize(ratio * d + (ratio * cos_incident - cos_transmitted) * normal);
        const Ray<Real> refraction{position - normal * epsilon_, transmitted};
        Vec3<Real> through = (1 - fresnel) * radiance(refraction, depth + 1);
        // Pre-2020 scenes describe glass by a Transparency colour that filters what passes.
        if (material.transparency != Vec3<Real>(0)) through *= material.transparency;
        return fresnel * radiance(reflection, depth + 1) + through;
    }

    const Geometry& geometry_;
    const LightSetT& lights_;
    const std::vector<Material<Real>>& materials_;
    Vec3<Real> ambient_light_;
    Vec3<Real> background_;
    IntegratorSettings settings_;
    Real epsilon_;
};

}  // namespace prism
