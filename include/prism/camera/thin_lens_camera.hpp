// The course's depth of field: a thin lens with a square aperture of side ApertureSize centred on
// the camera position, sharp at FocusDistance along the gaze. A pinhole ray through the image
// point meets the plane of focus at p = e + d t_fd, t_fd = FocusDistance / (d . gaze); the lens
// ray leaves a uniform point a of the aperture towards p (Shirley and Marschner, "Fundamentals of
// Computer Graphics" 4th ed., 13.5; the course's hw3 formulation). Aperture 0 is the pinhole.
#pragma once

#include <prism/camera/pinhole_camera.hpp>

namespace prism {

template <Scalar Real>
class ThinLensCamera {
public:
    ThinLensCamera(const scene::Camera& camera, int width, int height)
        : pinhole_(camera, width, height), aperture_(Real(camera.aperture_size)),
          focus_distance_(Real(camera.focus_distance)) {}

    int width() const { return pinhole_.width(); }
    int height() const { return pinhole_.height(); }
    bool has_aperture() const { return aperture_ > 0; }
    // The angle one pixel subtends at the image centre: the spread of a pixel's ray cone.
    Real pixel_spread() const { return pinhole_.pixel_spread(); }

    // The ray through the continuous image position (x, y) (as PinholeCamera::ray) leaving the
    // lens at `lens` in [0, 1)^2, at shutter instant `time`.
    Ray<Real> ray(Real x, Real y, const Vec2<Real>& lens, Real time) const {
        Ray<Real> ray = pinhole_.ray(x, y);
        ray.time = time;
        if (aperture_ > 0) {
            const Vec3<Real> focus = ray.origin + ray.direction * (focus_distance_ / glm::dot(ray.direction, pinhole_.forward()));
            ray.origin += aperture_ * ((lens.x - Real(0.5)) * pinhole_.right() + (lens.y - Real(0.5)) * pinhole_.up());
            ray.direction = unit_vector(focus - ray.origin);
        }
        return ray;
    }

    // The rays of a row's pixel centres (PinholeCamera::centre_rays), for a camera without an
    // aperture, whose rays are the pinhole's.
    template <std::size_t N>
    void centre_rays(int x0, int y, const std::array<Real, N>& times, std::array<Ray<Real>, N>& rays) const {
        pinhole_.centre_rays(x0, y, times, rays);
    }

private:
    PinholeCamera<Real> pinhole_;
    Real aperture_;
    Real focus_distance_;
};

}  // namespace prism
