// The course's Torrance-Sparrow microfacet BRDF (CENG795 "BRDFs" slides; Torrance and Sparrow
// 1967, Cook and Torrance 1982):
//     f(wi, wo) = kd / pi + ks D(alpha) F(beta) G(wi, wo) / (4 cos(theta_i) cos(theta_o)),
// - D(alpha) = (p + 2) / (2 pi) cos^p(alpha): Blinn's distribution of the microfacet normals,
//   alpha the angle between n and the half vector h, p the <Exponent>;
// - F(beta) = R0 + (1 - R0) (1 - cos beta)^5: Schlick's Fresnel, beta the angle between wo and h,
//   R0 = ((eta - 1) / (eta + 1))^2 from the material's RefractionIndex eta;
// - G = min(1, 2 (n.h)(n.wo) / (wo.h), 2 (n.h)(n.wi) / (wo.h)): the V-groove masking and
//   shadowing of Torrance and Sparrow;
// - kdfresnel="true": light the specular term reflects does not reach the diffuse one, kd (1 - F).
// No course scene with an expected image uses it: the formulas are the slides' as students'
// public renderers implement them.
#pragma once

#include <prism/material/brdf/lobe.hpp>

#include <algorithm>
#include <cmath>

namespace prism {

template <Scalar Real>
struct TorranceSparrow {
    Real exponent = 1;
    bool kdfresnel = false;
    Real refraction_index = 1;

    Vec3<Real> evaluate(const Vec3<Real>& kd, const Vec3<Real>& ks, const Vec3<Real>& n, const Vec3<Real>& wi,
                        const Vec3<Real>& wo) const {
        const Real cos_incident = glm::dot(n, wi);
        const Real cos_outgoing = glm::dot(n, wo);
        if (cos_incident <= 0 || cos_outgoing <= 0) return Vec3<Real>(0);
        const Vec3<Real> half = unit_vector(wi + wo);
        const Real cos_alpha = std::max(glm::dot(n, half), Real(0));
        const Real cos_beta = std::max(glm::dot(wo, half), Real(0));
        const Real distribution = (exponent + 2) / (2 * pi<Real>) * std::pow(cos_alpha, exponent);
        const Real r0 = square((refraction_index - 1) / (refraction_index + 1));
        const Real fresnel = r0 + (1 - r0) * std::pow(1 - cos_beta, Real(5));
        const Real geometry = cos_beta > 0 ? std::min({Real(1), 2 * cos_alpha * cos_outgoing / cos_beta,
                                                        2 * cos_alpha * cos_incident / cos_beta})
                                           : Real(0);
        const Vec3<Real> diffuse = kdfresnel ? kd * (1 - fresnel) : kd;
        return diffuse / pi<Real> +
               ks * (distribution * fresnel * geometry / (4 * cos_incident * cos_outgoing));
    }
    BlinnLobe<Real> lobe() const { return {exponent}; }

private:
    static Real square(Real x) { return x * x; }
};

}  // namespace prism
