// The specular lobes that the course's BRDFs sample, each with its sampler and its solid-angle
// pdf: the Phong lobe cos^p(alpha_r) around the mirror direction of wo, and the Blinn lobe
// cos^p(alpha_h) of the half vector around the normal (Lafortune and Willems 1994; Pharr, Jakob
// and Humphreys, PBR 3rd ed., sec. 14.1.1 for the half-vector Jacobian 1 / (4 wo.wh)).
#pragma once

#include <prism/math/vector.hpp>
#include <prism/sampling/hemisphere.hpp>

#include <algorithm>
#include <cmath>

namespace prism {

// `direction` mirrored about the unit `axis`: 2 (axis.direction) axis - direction.
template <Scalar Real>
Vec3<Real> mirrored(const Vec3<Real>& direction, const Vec3<Real>& axis) {
    return 2 * glm::dot(axis, direction) * axis - direction;
}

// cos^exponent, the specular term's power, for a term weighted by ks. A material with no
// specular reflectance (ks = 0: every wall and sphere of hw7's Cornell boxes) needs no power:
// glibc's powf for its Phong exponents of 90-600 was 8% of path_diffuse's time, and every value
// was multiplied by 0. With exponent >= 0 the power of a cosine clamped to [0, 1] is finite, so
// ks times it (or times a finite factor of it) is a zero, as ks times 0 is; kd plus either zero
// is kd's bits (for any kd but -0), so the BRDF's value does not change.
template <Scalar Real>
Real specular_power(const Vec3<Real>& ks, Real cosine, Real exponent) {
    if (ks == Vec3<Real>(0) && exponent >= 0) return 0;
    return std::pow(cosine, exponent);
}

// wi around the mirror direction r of wo with density (p + 1) / (2 pi) cos^p(angle(wi, r)).
// The same density serves both original and modified Phong: r.wi = wo.(mirror of wi).
template <Scalar Real>
struct PhongLobe {
    Real exponent = 1;

    Vec3<Real> sample(const Vec3<Real>& n, const Vec3<Real>& wo, const Vec2<Real>& u) const {
        return sample_power_cosine(mirrored(wo, n), exponent, u);
    }
    Real pdf(const Vec3<Real>& n, const Vec3<Real>& wi, const Vec3<Real>& wo) const {
        return power_cosine_pdf(glm::dot(mirrored(wo, n), wi), exponent);
    }
};

// wi = wo mirrored about a half vector h drawn with density (p + 1) / (2 pi) cos^p(theta_h)
// around n; the density of wi is that over 4 |wo.h|.
template <Scalar Real>
struct BlinnLobe {
    Real exponent = 1;

    Vec3<Real> sample(const Vec3<Real>& n, const Vec3<Real>& wo, const Vec2<Real>& u) const {
        return mirrored(wo, sample_power_cosine(n, exponent, u));
    }
    Real pdf(const Vec3<Real>& n, const Vec3<Real>& wi, const Vec3<Real>& wo) const {
        const Vec3<Real> sum = wi + wo;
        const Real length = glm::length(sum);
        if (length == 0) return 0;
        const Vec3<Real> half = sum / length;
        const Real wo_dot_half = std::abs(glm::dot(wo, half));
        if (wo_dot_half == 0) return 0;
        // h and -h mirror wo to the same wi, and one of them faces n: a drawn h with h.wo < 0
        // gives a wi below the surface, whose half vector wi + wo is -h.
        return power_cosine_pdf(std::abs(glm::dot(n, half)), exponent) / (4 * wo_dot_half);
    }
};

}  // namespace prism
