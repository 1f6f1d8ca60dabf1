// A material in the renderer's precision: the course's Blinn-Phong coefficients plus what the
// mirror, conductor and dielectric types add, and its BRDF (material/brdf.hpp).
#pragma once

#include <prism/material/brdf.hpp>
#include <prism/math/floating_point.hpp>
#include <prism/math/vector.hpp>
#include <prism/scene/scene.hpp>

#include <cmath>
#include <limits>

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
    // Where the Blinn-Phong power cos^phong_exponent stops mattering: at a cosine at most this,
    // the power is at most 2^-specular_negligible_log2 (blinn_phong_power_negligible). Textures
    // never change phong_exponent, so a textured copy keeps it right.
    Real phong_negligible_below = -1;

    explicit Material(const scene::Material& m)
        : type(m.type), ambient(m.ambient), diffuse(m.diffuse), specular(m.specular), mirror(m.mirror),
          phong_exponent(Real(m.phong_exponent)), refraction_index(Real(m.refraction_index)),
          absorption_index(Real(m.absorption_index)), absorption_coefficient(m.absorption_coefficient),
          transparency(m.transparency), roughness(Real(m.roughness)),
          brdf(make_brdf<Real>(m)), brdf_given(m.brdf.has_value()),
          phong_negligible_below(negligible_power_below(phong_exponent)) {}

    // 2^-K with K = digits + 16 (40 in float, 69 in double): a power that small, times a
    // specular coefficient of at most 2^13 times the diffuse term, is below half an ulp of it.
    static constexpr int specular_negligible_log2 = std::numeric_limits<Real>::digits + 16;

    // The largest cosine x (rounded down, then one more step) with x^exponent <= 2^-K; -1 where
    // no cosine qualifies (an exponent of 0, negative or NaN, for which cos^0 = 1).
    static Real negligible_power_below(Real exponent) {
        if (!(exponent > 0)) return -1;
        const double exact = std::exp2(-double(specular_negligible_log2) / double(exponent)) * (1 - 1e-9);
        Real below = Real(exact);
        if (double(below) > exact) below = std::nextafter(below, Real(0));
        return below;
    }
};

// Whether diffuse + specular * cos_half^phong_exponent rounds to diffuse + specular * 0, so that
// the power can be left out (glibc's powf was 11% of hw2 mirror_room, exponent 100 on every
// material). Where cos_half <= material.phong_negligible_below the power is at most
// 2^-K (1 + 2^-20), pow's own error included (glibc's: under 1 ulp); where each specular
// coefficient times that is below its diffuse term times 2^-(digits + 3), the rounded product is
// under half an ulp of the diffuse term, and the sum rounds back to it, as it does with the
// product by 0. Negative coefficients and diffuse terms below 1e-20 take the power.
template <Scalar Real>
bool blinn_phong_power_negligible(const Material<Real>& material, Real cos_half, const Vec3<Real>& diffuse) {
    if (!(cos_half <= material.phong_negligible_below)) return false;
    static_assert(Material<Real>::specular_negligible_log2 == std::numeric_limits<Real>::digits + 16);
    constexpr Real bound = unit_roundoff<Real> * Real(0x1p-16) * (1 + Real(0x1p-20));  // 2^-K (1 + 2^-20)
    constexpr Real scale = unit_roundoff<Real> / 8;                                   // 2^-(digits + 3)
    for (int c = 0; c < 3; ++c)
        if (!(material.specular[c] >= 0 && diffuse[c] >= Real(1e-20) && material.specular[c] * bound < diffuse[c] * scale))
            return false;
    return true;
}

// cos_half^phong_exponent as std::pow gives it, without the call for the exponent 1 (the course's
// default, most hw1-hw4 materials, VeachAjar's specular walls): pow(x, 1) is x for every float and
// every double, NaN aside (pow's error is under 1 ulp, and x is representable; checked for all
// 2^32 floats against glibc's powf), so the shortcut gives pow's bits.
template <Scalar Real>
Real blinn_phong_power(Real cos_half, Real phong_exponent) {
    return phong_exponent == 1 ? cos_half : std::pow(cos_half, phong_exponent);
}

}  // namespace prism
