// An HDR image around the scene, seen in a direction: the two layouts of the course's
// SphericalDirectionalLight (CENG795 hw5) and bilinear lookup of their radiance.
//
// Image coordinates (u, v) are in [0, 1]^2, u to the right, v down from the top row; pixel (x, y)
// has its centre at ((x + 1/2) / width, (y + 1/2) / height).
//
// - Lat-long (equirectangular), the course's mapping: u = (1 + atan2(d.x, -d.z) / pi) / 2,
//   v = acos(d.y) / pi. The top row is +Y, the bottom row -Y; the middle column (u = 1/2) is -Z,
//   u = 3/4 is +X, u = 1/4 is -X, and the left and right edges meet at +Z. The files in
//   shared/envmaps are used as stored: the same orientation as the course's maps (the derived
//   Uffizi probe, made with the course's probe mapping from spica_uffizi_latlong.hdr, agrees with
//   that file direction by direction under this mapping: tests/test_environment_light.cpp).
// - Light probe (angular map; Debevec, "Rendering Synthetic Objects into Real Scenes", SIGGRAPH
//   1998, and his Light Probe Image Gallery): the disc inscribed in the image, its centre -Z,
//   right +X, up +Y; the distance from the centre is proportional to the angle from -Z, so the
//   rim is +Z. With r = acos(-d.z) / (pi sqrt(d.x^2 + d.y^2)): u = (1 + r d.x) / 2,
//   v = (1 - r d.y) / 2. Pixels outside the disc are not directions (black in the files).
//
// Solid angle per unit image area (the Jacobians that turn a density over the image into one
// over directions, pdf_omega = pdf_uv / J):
// - lat-long: theta = pi v, phi = 2 pi u - pi, d omega = sin theta d theta d phi, so
//   J = 2 pi^2 sin(pi v);
// - probe: with rho the distance from the centre in the unit disc (rho = 1 at the rim) and alpha =
//   pi rho the angle from -Z, d omega = sin(alpha) d alpha d psi = pi sin(pi rho) d rho d psi,
//   the disc's area element is rho d rho d psi = 4 du dv, so J = 4 pi sin(pi rho) / rho
//   (4 pi^2 at the centre, 0 at and beyond the rim). Both integrate to 4 pi over the image.
#pragma once

#include <prism/image/image.hpp>
#include <prism/math/vector.hpp>
#include <prism/scene/scene.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>

namespace prism {

template <Scalar Real>
Vec2<Real> latlong_coordinates(const Vec3<Real>& direction) {
    const Real u = (1 + std::atan2(direction.x, -direction.z) / pi<Real>) / 2;
    const Real v = std::acos(std::clamp(direction.y, Real(-1), Real(1))) / pi<Real>;
    return {u, v};
}

template <Scalar Real>
Vec3<Real> latlong_direction(const Vec2<Real>& uv) {
    const Real phi = pi<Real> * (2 * uv.x - 1);
    const Real theta = pi<Real> * uv.y;
    const Real sin_theta = std::sin(theta);
    return {sin_theta * std::sin(phi), std::cos(theta), -sin_theta * std::cos(phi)};
}

template <Scalar Real>
Real latlong_jacobian(const Vec2<Real>& uv) {
    return 2 * pi<Real> * pi<Real> * std::max(std::sin(pi<Real> * uv.y), Real(0));
}

template <Scalar Real>
Vec2<Real> probe_coordinates(const Vec3<Real>& direction) {
    const Real planar = std::sqrt(direction.x * direction.x + direction.y * direction.y);
    // Straight ahead (-Z) is the centre; straight behind (+Z) is the whole rim: pick its
    // rightmost point.
    if (!(planar > 0)) return direction.z <= 0 ? Vec2<Real>(Real(0.5)) : Vec2<Real>(1, Real(0.5));
    const Real r = std::acos(std::clamp(-direction.z, Real(-1), Real(1))) / (pi<Real> * planar);
    return {(1 + r * direction.x) / 2, (1 - r * direction.y) / 2};
}

// Points outside the disc are taken to its rim (+Z).
template <Scalar Real>
Vec3<Real> probe_direction(const Vec2<Real>& uv) {
    const Real a = 2 * uv.x - 1, b = 1 - 2 * uv.y;
    const Real rho = std::sqrt(a * a + b * b);
    if (!(rho > 0)) return {0, 0, -1};
    const Real alpha = pi<Real> * std::min(rho, Real(1));
    const Real sin_alpha = std::sin(alpha);
    return {sin_alpha * a / rho, sin_alpha * b / rho, -std::cos(alpha)};
}

template <Scalar Real>
Real probe_jacobian(const Vec2<Real>& uv) {
    const Real a = 2 * uv.x - 1, b = 1 - 2 * uv.y;
    const Real rho = std::sqrt(a * a + b * b);
    if (rho >= 1) return 0;
    if (rho < Real(1e-4)) return 4 * pi<Real> * pi<Real>;  // sin(pi rho) / rho -> pi
    return 4 * pi<Real> * std::sin(pi<Real> * rho) / rho;
}

// An image with its layout and a radiance scale (the light's). Copies share the pixels.
template <Scalar Real>
class EnvironmentMap {
public:
    EnvironmentMap(std::shared_ptr<const Image> image, scene::EnvironmentLayout layout, const Vec3<Real>& scale = Vec3<Real>(1))
        : image_(std::move(image)), layout_(layout), scale_(scale) {}

    const Image& image() const { return *image_; }
    const std::shared_ptr<const Image>& shared_image() const { return image_; }
    scene::EnvironmentLayout layout() const { return layout_; }
    const Vec3<Real>& scale() const { return scale_; }

    Vec2<Real> coordinates(const Vec3<Real>& direction) const {
        return layout_ == scene::EnvironmentLayout::latlong ? latlong_coordinates(direction) : probe_coordinates(direction);
    }
    Vec3<Real> direction(const Vec2<Real>& uv) const {
        return layout_ == scene::EnvironmentLayout::latlong ? latlong_direction(uv) : probe_direction(uv);
    }
    Real jacobian(const Vec2<Real>& uv) const {
        return layout_ == scene::EnvironmentLayout::latlong ? latlong_jacobian(uv) : probe_jacobian(uv);
    }

    // Bilinear between the four nearest pixel centres, unscaled. Lat-long maps wrap around in u
    // (the left and right edges are the same meridian); rows, and both axes of a probe, clamp
    // at the border.
    Vec3<Real> lookup(const Vec2<Real>& uv) const {
        const Image& image = *image_;
        const Real x = uv.x * Real(image.width) - Real(0.5);
        const Real y = uv.y * Real(image.height) - Real(0.5);
        const Real x_floor = std::floor(x), y_floor = std::floor(y);
        const Real fx = x - x_floor, fy = y - y_floor;
        const int x0 = int(x_floor), y0 = int(y_floor);
        int c0, c1;
        if (layout_ == scene::EnvironmentLayout::latlong) {
            c0 = repeat_index(x0, image.width);
            c1 = repeat_next(c0, image.width);
        } else {
            c0 = std::clamp(x0, 0, image.width - 1);
            c1 = std::clamp(x0 + 1, 0, image.width - 1);
        }
        const int r0 = std::clamp(y0, 0, image.height - 1), r1 = std::clamp(y0 + 1, 0, image.height - 1);
        auto texel = [&](int c, int r) { return Vec3<Real>(image(c, r)); };
        return (1 - fy) * ((1 - fx) * texel(c0, r0) + fx * texel(c1, r0)) +
               fy * ((1 - fx) * texel(c0, r1) + fx * texel(c1, r1));
    }

    // The scaled radiance arriving from `direction` (unit): what a ray that escapes the scene
    // along it sees.
    Vec3<Real> radiance(const Vec3<Real>& direction) const { return scale_ * lookup(coordinates(direction)); }

private:
    std::shared_ptr<const Image> image_;
    scene::EnvironmentLayout layout_ = scene::EnvironmentLayout::latlong;
    Vec3<Real> scale_{1};
};

}  // namespace prism
