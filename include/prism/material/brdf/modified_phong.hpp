// The course's modified Phong BRDF (CENG795 "BRDFs" slides; Lafortune and Willems 1994):
//     f(wi, wo) = kd + ks cos^p(alpha_r),                          normalized="false"
//     f(wi, wo) = kd / pi + ks (p + 2) / (2 pi) cos^p(alpha_r),    normalized="true",
// alpha_r the angle between wo and wi mirrored about n. Dropping the original's 1 / cos(theta_i)
// makes it reciprocal; the factors (p + 2) / (2 pi) and 1 / pi make the directional albedo of
// each term at most 1 (of the specular term exactly 1 at normal incidence).
#pragma once

#include <prism/material/brdf/lobe.hpp>

#include <algorithm>
#include <cmath>

namespace prism {

template <Scalar Real>
struct ModifiedPhong {
    Real exponent = 1;
    bool normalized = false;

    Vec3<Real> evaluate(const Vec3<Real>& kd, const Vec3<Real>& ks, const Vec3<Real>& n, const Vec3<Real>& wi,
                        const Vec3<Real>& wo) const {
        if (glm::dot(n, wi) <= 0) return Vec3<Real>(0);
        const Real cos_alpha = std::max(glm::dot(mirrored(wi, n), wo), Real(0));
        const Real specular = specular_power(ks, cos_alpha, exponent);
        if (!normalized) return kd + ks * specular;
        return kd / pi<Real> + ks * ((exponent + 2) / (2 * pi<Real>) * specular);
    }
    PhongLobe<Real> lobe() const { return {exponent}; }
};

}  // namespace prism
