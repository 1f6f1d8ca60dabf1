// The course's original Blinn-Phong BRDF (CENG795 "BRDFs" slides; Blinn 1977 written as a BRDF):
//     f(wi, wo) = kd + ks cos^p(alpha_h) / cos(theta_i),
// alpha_h the angle between n and the half vector of wi and wo. Times cos(theta_i) it is the
// Blinn-Phong shading of hw1-hw5, so it is what a material without a BRDF means (material/brdf.hpp).
#pragma once

#include <prism/material/brdf/lobe.hpp>

#include <algorithm>
#include <cmath>

namespace prism {

template <Scalar Real>
struct OriginalBlinnPhong {
    Real exponent = 1;

    Vec3<Real> evaluate(const Vec3<Real>& kd, const Vec3<Real>& ks, const Vec3<Real>& n, const Vec3<Real>& wi,
                        const Vec3<Real>& wo) const {
        const Real cos_incident = glm::dot(n, wi);
        if (cos_incident <= 0) return Vec3<Real>(0);
        const Vec3<Real> half = unit_vector(wi + wo);
        const Real cos_alpha = std::max(glm::dot(n, half), Real(0));
        return kd + ks * (specular_power(ks, cos_alpha, exponent) / cos_incident);
    }
    BlinnLobe<Real> lobe() const { return {exponent}; }
};

}  // namespace prism
