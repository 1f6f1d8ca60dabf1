// The closed set of the course's BRDFs (CENG795 hw6 <BRDFs>) and what an integrator asks of a
// material's: f(wi, wo), a direction drawn in proportion to it, and that draw's pdf. One header
// per model in material/brdf/; a std::variant dispatches per hit without virtual calls.
//
// Conventions: n is the unit shading normal on the side of wo; wi points to the light, wo to the
// viewer; all unit vectors. f is not multiplied by cos(theta_i): f(wi, wo) cos(theta_i) is what
// multiplies the radiance arriving along wi.
//
// A material without a BRDF is the course's original Blinn-Phong with its PhongExponent: times
// cos(theta_i) that is exactly hw1-hw5's (kd cos(theta_i) + ks cos^p(alpha_h)) E. (The Whitted
// integrator keeps its own inlined form for such materials, so hw1-hw5 images stay bit-identical.)
//
// Sampling: a mixture of the cosine-weighted hemisphere (the diffuse term) and the model's
// specular lobe (material/brdf/lobe.hpp), chosen with probability in proportion to the mean of
// ks against that of kd; the pdf is the mixture's, over the whole sphere.
#pragma once

#include <prism/material/brdf/modified_blinn_phong.hpp>
#include <prism/material/brdf/modified_phong.hpp>
#include <prism/material/brdf/original_blinn_phong.hpp>
#include <prism/material/brdf/original_phong.hpp>
#include <prism/material/brdf/torrance_sparrow.hpp>
#include <prism/math/force_inline.hpp>
#include <prism/sampling/hemisphere.hpp>
#include <prism/scene/scene.hpp>

#include <algorithm>
#include <variant>

namespace prism {

template <Scalar Real>
using Brdf = std::variant<OriginalBlinnPhong<Real>, OriginalPhong<Real>, ModifiedPhong<Real>, ModifiedBlinnPhong<Real>,
                          TorranceSparrow<Real>>;

// The model a scene material names, or the course's default for one that names none.
template <Scalar Real>
Brdf<Real> make_brdf(const scene::Material& material) {
    if (!material.brdf) return OriginalBlinnPhong<Real>{Real(material.phong_exponent)};
    const scene::Brdf& b = *material.brdf;
    const Real exponent = Real(b.exponent);
    switch (b.model) {
        case scene::BrdfModel::original_phong: return OriginalPhong<Real>{exponent};
        case scene::BrdfModel::modified_phong: return ModifiedPhong<Real>{exponent, b.normalized};
        case scene::BrdfModel::original_blinn_phong: return OriginalBlinnPhong<Real>{exponent};
        case scene::BrdfModel::modified_blinn_phong: return ModifiedBlinnPhong<Real>{exponent, b.normalized};
        case scene::BrdfModel::torrance_sparrow:
            return TorranceSparrow<Real>{exponent, b.kdfresnel, Real(material.refraction_index),
                                         Real(material.absorption_index)};
    }
    return OriginalBlinnPhong<Real>{Real(material.phong_exponent)};
}

template <Scalar Real>
struct Material;

// f applied to the model `brdf` holds: a switch the caller inlines, where std::visit's table of
// calls stayed a function of its own (3% of path_diffuse's instructions, evaluate_brdf's).
template <Scalar Real, class F>
PRISM_FORCE_INLINE inline decltype(auto) visit_brdf(const Brdf<Real>& brdf, F&& f) {
    static_assert(std::variant_size_v<Brdf<Real>> == 5, "a case for each model");
    switch (brdf.index()) {
        case 0: return f(*std::get_if<0>(&brdf));
        case 1: return f(*std::get_if<1>(&brdf));
        case 2: return f(*std::get_if<2>(&brdf));
        case 3: return f(*std::get_if<3>(&brdf));
        default: return f(*std::get_if<4>(&brdf));
    }
}

template <Scalar Real>
struct BrdfSample {
    Vec3<Real> direction{0};  // wi
    Vec3<Real> value{0};      // f(wi, wo); zero when wi fell below the surface
    Real pdf = 0;             // solid-angle density of direction
};

namespace detail::brdf {

// The probability of drawing from the specular lobe rather than the cosine hemisphere.
template <Scalar Real>
Real lobe_probability(const Vec3<Real>& kd, const Vec3<Real>& ks) {
    const Real diffuse = (kd.x + kd.y + kd.z) / 3;
    const Real specular = (ks.x + ks.y + ks.z) / 3;
    if (diffuse + specular <= 0) return Real(0.5);
    return specular / (diffuse + specular);
}

template <Scalar Real, class Model>
Real mixture_pdf(const Model& model, Real lobe_weight, const Vec3<Real>& n, const Vec3<Real>& wi,
                 const Vec3<Real>& wo) {
    const Real cosine = std::max(glm::dot(n, wi), Real(0)) / pi<Real>;
    // Without a specular term the lobe is never drawn (weight 0), and its density (a power) is
    // left out: 0 times a finite, non-negative density is the +0 added here, the same bits.
    if (lobe_weight == 0) return (1 - lobe_weight) * cosine + Real(0);
    return (1 - lobe_weight) * cosine + lobe_weight * model.lobe().pdf(n, wi, wo);
}

}  // namespace detail::brdf

// f(wi, wo), not multiplied by cos(theta_i).
template <Scalar Real>
Vec3<Real> evaluate_brdf(const Material<Real>& m, const Vec3<Real>& n, const Vec3<Real>& wi, const Vec3<Real>& wo) {
    return visit_brdf(m.brdf, [&](const auto& model) { return model.evaluate(m.diffuse, m.specular, n, wi, wo); });
}

// The solid-angle pdf with which sample_brdf draws wi given wo.
template <Scalar Real>
Real brdf_pdf(const Material<Real>& m, const Vec3<Real>& n, const Vec3<Real>& wi, const Vec3<Real>& wo) {
    const Real lobe_weight = detail::brdf::lobe_probability(m.diffuse, m.specular);
    return visit_brdf(m.brdf,
                      [&](const auto& model) { return detail::brdf::mixture_pdf(model, lobe_weight, n, wi, wo); });
}

// u uniform in [0, 1)^2: u.x picks the lobe and is stretched back to [0, 1) for the direction.
template <Scalar Real>
BrdfSample<Real> sample_brdf(const Material<Real>& m, const Vec3<Real>& n, const Vec3<Real>& wo, const Vec2<Real>& u) {
    const Real lobe_weight = detail::brdf::lobe_probability(m.diffuse, m.specular);
    return visit_brdf(
        m.brdf, [&](const auto& model) {
            BrdfSample<Real> sample;
            if (u.x < lobe_weight) {
                sample.direction = model.lobe().sample(n, wo, Vec2<Real>(u.x / lobe_weight, u.y));
            } else {
                const Real stretched = (u.x - lobe_weight) / (1 - lobe_weight);
                sample.direction = sample_cosine_hemisphere(n, Vec2<Real>(stretched, u.y));
            }
            sample.pdf = detail::brdf::mixture_pdf(model, lobe_weight, n, sample.direction, wo);
            sample.value = model.evaluate(m.diffuse, m.specular, n, sample.direction, wo);
            return sample;
        });
}

}  // namespace prism
