// The course's modified Blinn-Phong BRDF (CENG795 "BRDFs" slides):
//     f(wi, wo) = kd + ks cos^p(alpha_h),                          normalized="false"
//     f(wi, wo) = kd / pi + ks (p + 8) / (8 pi) cos^p(alpha_h),    normalized="true",
// alpha_h the angle between n and the half vector of wi and wo. (p + 8) / (8 pi) is the usual
// approximate normalisation (Akenine-Moller, Haines and Hoffman, Real-Time Rendering 3rd ed.,
// sec. 7.6; Giesen 2009 derives it): the albedo stays at most 1 without being exactly 1.
#pragma once

#include <prism/material/brdf/lobe.hpp>

#include <algorithm>
#include <cmath>

namespace prism {

template <Scalar Real>
struct ModifiedBlinnPhong {
    Real exponent = 1;
    bool normalized = false;

    Vec3<Real> evaluate(const Vec3<Real>& kd, const Vec3<Real>& ks, const Vec3<Real>& n, const Vec3<Real>& wi,
                        const Vec3<Real>& wo) const {
        if (glm::dot(n, wi) <= 0) return Vec3<Real>(0);
        const Vec3<Real> half = unit_vector(wi + wo);
        const Real specular = specular_power(ks, std::max(glm::dot(n, half), Real(0)), exponent);
        if (!normalized) return kd + ks * specular;
        return kd / pi<Real> + ks * ((exponent + 8) / (8 * pi<Real>) * specular);
    }
    BlinnLobe<Real> lobe() const { return {exponent}; }
};

}  // namespace prism
