// The course's pinhole camera: an image plane at NearDistance along Gaze, bounded by NearPlane
// (left, right, bottom, top), with pixel (i, j) sampled at s = q + su u - sv v from the top-left
// corner q. Built from the plain camera, possibly at a reduced resolution.
#pragma once

#include <prism/geometry/ray.hpp>
#include <prism/scene/scene.hpp>
#include <prism/simd/pack.hpp>

#include <array>
#include <cmath>

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

    // ray(Real(x0 + i) + 0.5, Real(y) + 0.5) for i < N, the pixel centres of a row, at the
    // instants times[i]: each the bits ray gives it (the same operations in the same order,
    // lane by lane, -ffp-contract=off), eight lanes at a time with the square roots and
    // divisions side by side (simd::Pack: GCC does not vectorise std::sqrt in a plain loop
    // without -fno-math-errno).
    template <std::size_t N>
    void centre_rays(int x0, int y, const std::array<Real, N>& times, std::array<Ray<Real>, N>& rays) const {
        using Lanes = simd::Pack<Real, 8>;
        static_assert(N % 8 == 0);
        const Vec3<Real> down = (Real(y) + Real(0.5)) * step_v_;
        const Lanes left[3] = {Lanes::broadcast(top_left_.x), Lanes::broadcast(top_left_.y), Lanes::broadcast(top_left_.z)};
        const Lanes step[3] = {Lanes::broadcast(step_u_.x), Lanes::broadcast(step_u_.y), Lanes::broadcast(step_u_.z)};
        const Lanes below[3] = {Lanes::broadcast(down.x), Lanes::broadcast(down.y), Lanes::broadcast(down.z)};
        alignas(64) std::array<Real, N> direction[3];
        for (std::size_t first = 0; first < N; first += 8) {
            alignas(64) Real centres[8];
            for (int i = 0; i < 8; ++i) centres[i] = Real(x0 + static_cast<int>(first) + i) + Real(0.5);
            const Lanes x = Lanes::load(centres);
            // top_left_ + x * step_u_ + y * step_v_, as glm sums it (left to right), and
            // unit_vector's v * (1 / sqrt(v . v)).
            Lanes along[3];
            for (int axis = 0; axis < 3; ++axis) along[axis] = (left[axis] + x * step[axis]) + below[axis];
            const Lanes scale =
                Lanes::broadcast(Real(1)) / simd::sqrt((along[0] * along[0] + along[1] * along[1]) + along[2] * along[2]);
            for (int axis = 0; axis < 3; ++axis) (along[axis] * scale).store(direction[axis].data() + first);
        }
        for (std::size_t i = 0; i < N; ++i)
            rays[i] = Ray<Real>{origin_, Vec3<Real>(direction[0][i], direction[1][i], direction[2][i]), Real(0),
                                infinity<Real>, times[i]};
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
