// The course's original Phong BRDF (CENG795 "BRDFs" slides; Phong 1975 written as a BRDF):
//     f(wi, wo) = kd + ks cos^p(alpha_r) / cos(theta_i),
// alpha_r the angle between wo and wi mirrored about n. Times cos(theta_i) it is the Phong
// shading of the course's first homeworks. Not reciprocal and not energy conserving: the
// reasons the course introduces the modified form (tests/test_brdf.cpp shows both).
#pragma once

#include <prism/material/brdf/lobe.hpp>

#include <algorithm>
#include <cmath>

namespace prism {

template <Scalar Real>
struct OriginalPhong {
    Real exponent = 1;

    Vec3<Real> evaluate(const Vec3<Real>& kd, const Vec3<Real>& ks, const Vec3<Real>& n, const Vec3<Real>& wi,
                        const Vec3<Real>& wo) const {
        const Real cos_incident = glm::dot(n, wi);
        if (cos_incident <= 0) return Vec3<Real>(0);
        const Real cos_alpha = std::max(glm::dot(mirrored(wi, n), wo), Real(0));
        return kd + ks * (specular_power(ks, cos_alpha, exponent) / cos_incident);
    }
    PhongLobe<Real> lobe() const { return {exponent}; }
};

}  // namespace prism
