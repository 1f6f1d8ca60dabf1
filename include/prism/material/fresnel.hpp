// Fresnel reflectance for unpolarised light, averaged over the two polarisations, as the course
// gives it: dielectrics from both refraction indices and the two cosines; conductors from the
// refraction index n and the absorption index k (the usual approximation, e.g. Akenine-Möller
// et al.; pbrt's FrConductor gives the exact form that agrees closely at normal incidence).
#pragma once

#include <prism/math/vector.hpp>

#include <algorithm>
#include <cmath>

namespace prism {

// cos_incident and cos_transmitted are both non-negative; n1 is the side the light arrives on.
template <Scalar Real>
inline Real fresnel_dielectric(Real cos_incident, Real cos_transmitted, Real n1, Real n2) {
    const Real parallel = (n2 * cos_incident - n1 * cos_transmitted) / (n2 * cos_incident + n1 * cos_transmitted);
    const Real perpendicular = (n1 * cos_incident - n2 * cos_transmitted) / (n1 * cos_incident + n2 * cos_transmitted);
    return (parallel * parallel + perpendicular * perpendicular) / 2;
}

template <Scalar Real>
inline Real fresnel_conductor(Real cos_incident, Real n, Real k) {
    const Real cos2 = cos_incident * cos_incident;
    const Real n2k2 = n * n + k * k;
    const Real two_n_cos = 2 * n * cos_incident;
    const Real rs = (n2k2 - two_n_cos + cos2) / (n2k2 + two_n_cos + cos2);
    const Real rp = (n2k2 * cos2 - two_n_cos + 1) / (n2k2 * cos2 + two_n_cos + 1);
    return (rs + rp) / 2;
}

}  // namespace prism
