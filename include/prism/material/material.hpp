// A material in the renderer's precision: the course's Blinn-Phong coefficients plus what the
// mirror, conductor and dielectric types add, and its BRDF (material/brdf.hpp).
#pragma once

#include <prism/material/brdf.hpp>
#include <prism/math/vector.hpp>
#include <prism/scene/scene.hpp>

namespace prism {

template <Scalar Real>
struct Material {
    scene::MaterialType type = scene::MaterialType::blinn_phong;
    Vec3<Real> ambient{0}, diffuse{0}, specular{0}, mirror{0};
    Real phong_exponent = 1;
    Real refraction_index = 1;
    Real absorption_index = 0;
    Vec3<Real> absorption_coefficient{0};
    Vec3<Real> transparency{0};
    Real roughness = 0;  // perturbs reflected and refracted directions (render/whitted_integrator.hpp)
    Brdf<Real> brdf;     // the course's original Blinn-Phong unless the material names a BRDF
    bool brdf_given = false;

    explicit Material(const scene::Material& m)
        : type(m.type), ambient(m.ambient), diffuse(m.diffuse), specular(m.specular), mirror(m.mirror),
          phong_exponent(Real(m.phong_exponent)), refraction_index(Real(m.refraction_index)),
          absorption_index(Real(m.absorption_index)), absorption_coefficient(m.absorption_coefficient),
          transparency(m.transparency), roughness(Real(m.roughness)),
          brdf(make_brdf<Real>(m)), brdf_given(m.brdf.has_value()) {}
};

}  // namespace prism
