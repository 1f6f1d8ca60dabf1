// The course's pinhole camera: an image plane at NearDistance along Gaze, bounded by NearPlane
// (left, right, bottom, top), with pixel (i, j) sampled at s = q + su u - sv v from the top-left
// corner q. Built from the plain camera, possibly at a reduced resolution.
#pragma once

#include <prism/geometry/ray.hpp>
#include <prism/scene/scene.hpp>

namespace prism {

template <Scalar Real>
class PinholeCamera {
public:
    PinholeCamera(const scene::Camera& camera, int width, int height) : width_(width), height_(height) {
        const glm::dvec3 w = -glm::normalize(camera.gaze);
        glm::dvec3 u = glm::normalize(glm::cross(camera.up, w));
        const glm::dvec3 v = glm::cross(w, u);
        if (camera.left_handed) u = -u;
        const glm::dvec3 m = camera.position - w * camera.near_distance;
        const glm::dvec3 q = m + camera.near_left * u + camera.near_top * v;
        origin_ = Vec3<Real>(camera.position);
        u_ = Vec3<Real>(u);
        v_ = Vec3<Real>(v);
        forward_ = Vec3<Real>(-w);
        top_left_ = Vec3<Real>(q - camera.position);
        step_u_ = Vec3<Real>(u * ((camera.near_right - camera.near_left) / width));
        step_v_ = Vec3<Real>(-v * ((camera.near_top - camera.near_bottom) / height));
    }

    int width() const { return width_; }
    int height() const { return height_; }

    // A unit-direction ray through the continuous image position (x, y), x in [0, width) from
    // the left, y in [0, height) from the top; pixel centres are at +0.5.
    Ray<Real> ray(Real x, Real y) const {
        return {origin_, unit_vector(top_left_ + x * step_u_ + y * step_v_), Real(0), infinity<Real>};
    }

    // The camera's frame: position, the image plane's right (u) and up (v) axes, and the unit
    // gaze. A thin lens (camera/thin_lens_camera.hpp) spreads its aperture along u and v.
    const Vec3<Real>& position() const { return origin_; }
    const Vec3<Real>& right() const { return u_; }
    const Vec3<Real>& up() const { return v_; }
    const Vec3<Real>& forward() const { return forward_; }
    Real pixel_spread() const { return glm::length(step_v_) / glm::length(top_left_ + step_u_ * Real(width_ / 2) + step_v_ * Real(height_ / 2)); }

private:
    int width_, height_;
    Vec3<Real> origin_, top_left_, step_u_, step_v_;
    Vec3<Real> u_{1, 0, 0}, v_{0, 1, 0}, forward_{0, 0, -1};
};

}  // namespace prism
