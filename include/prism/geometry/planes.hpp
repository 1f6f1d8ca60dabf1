// The course's infinite planes. PlaneShape is one plane and the bound on a hit point's error
// that lets rays leave it; PlaneSet is what an index tests of them. Planes are unbounded, so no
// index holds them: every ray tests each one, eight at a time in SIMD lanes.
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/geometry/hit.hpp>
#include <prism/geometry/ray.hpp>
#include <prism/geometry/surface_error.hpp>
#include <prism/scene/scene.hpp>
#include <prism/simd/pack.hpp>

#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

namespace prism {

template <Scalar Real>
struct PlaneShape {
    Vec3<Real> point{0};
    Vec3<Real> normal{0, 1, 0};  // unit

    // The scene's plane placed by its transformation (in double, rounded once).
    static PlaneShape of(const scene::Plane& plane) {
        const glm::dvec3 point = glm::dvec3(plane.transform * glm::dvec4(plane.point, 1.0));
        const glm::dvec3 normal = glm::normalize(glm::transpose(glm::inverse(glm::dmat3(plane.transform))) * plane.normal);
        return {Vec3<Real>(point), Vec3<Real>(normal)};
    }

    // The hit point reprojected onto the plane, p - n ((p - q) . n), with a bound on its error
    // along each axis. Planes are not in pbrt's set, so the bound is derived here: the exact
    // reprojection of the computed p lies on the plane whatever p's own error; computing it
    // rounds p - q and the dot product (gamma(4) of sum |n_i| (|p_i| + |q_i|)) and the final
    // subtraction (u |p'| and u |n d|). gamma(6) (|p| + |p'| + |q|) + gamma(2) |d| covers them
    // per axis, and d . |n| of it bounds the distance to the plane.
    PointWithError<Real> hit_point(const Vec3<Real>& approximate) const {
        const Real d = glm::dot(approximate - point, normal);
        const Vec3<Real> projected = approximate - normal * d;
        return {projected, gamma<Real>(6) * (abs_each(approximate) + abs_each(projected) + abs_each(point)) +
                               Vec3<Real>(gamma<Real>(2) * std::abs(d))};
    }

    // Forced inline: out of line, the planes' loop in front of every shadow ray's light took 17%
    // of hw2 mirror_room (5 planes).
    PRISM_FORCE_INLINE bool intersect(const Ray<Real>& ray, Real t_min, Real t_max, Real& t_hit) const {
        const Real denominator = glm::dot(ray.direction, normal);
        if (denominator == 0) return false;
        const Real numerator = glm::dot(point - ray.origin, normal);
        // Opposite signs (or a zero numerator) give a t of at most 0, which no t_min >= 0
        // accepts: the division is left out (planes behind the ray, half of a room's walls).
        if (t_min >= 0 && (numerator == 0 || std::signbit(numerator) != std::signbit(denominator))) return false;
        const Real t = numerator / denominator;
        if (!(t > t_min && t <= t_max)) return false;
        t_hit = t;
        return true;
    }
};

// A scene's planes, eight to a block, SoA, for one SIMD pass of PlaneShape::intersect's
// arithmetic. Plane p is object first_object + p (Hit::object), after the scene's instances.
template <Scalar Real>
class PlaneSet {
public:
    static constexpr int width = 8;

    PlaneSet(const scene::Scene& scene, std::uint32_t first_object) : first_object_(first_object) {
        for (std::size_t p = 0; p < scene.planes.size(); ++p) {
            const PlaneShape<Real> plane = PlaneShape<Real>::of(scene.planes[p]);
            if (p % width == 0) blocks_.emplace_back();
            Block& block = blocks_.back();
            const std::size_t lane = p % width;
            for (int axis = 0; axis < 3; ++axis) {
                block.point[axis][lane] = plane.point[axis];
                block.normal[axis][lane] = plane.normal[axis];
            }
            block.lanes |= std::uint32_t(1) << lane;
        }
    }

    bool empty() const { return blocks_.empty(); }

    // The closest plane in (ray.t_min, ray.t_max] (ray.t_max lowered to it, hit filled): the
    // lanes are accepted in order as one plane after another would be, so the hit is the
    // scalar loop's. cull_back_faces (culls_planes): planes met from behind are skipped.
    // The test for no planes is inlined into the caller (the index's entries ask every ray):
    // most scenes have none, and the call into an empty loop was 0.8% of the dragon's
    // closest-hit profile.
    PRISM_FORCE_INLINE bool closest(Ray<Real>& ray, Hit<Real>& hit, bool cull_back_faces) const {
        return !blocks_.empty() && closest_in_blocks(ray, hit, cull_back_faces);
    }

    // Whether a plane lies in (ray.t_min, ray.t_max).
    PRISM_FORCE_INLINE bool occludes(const Ray<Real>& ray) const { return !blocks_.empty() && occludes_in_blocks(ray); }

private:
    bool closest_in_blocks(Ray<Real>& ray, Hit<Real>& hit, bool cull_back_faces) const {
        bool found = false;
        for (std::size_t b = 0; b < blocks_.size(); ++b) {
            alignas(64) Real t[width];
            alignas(64) Real denominator[width];
            for (std::uint32_t lanes = distances(blocks_[b], ray, t, denominator); lanes != 0; lanes &= lanes - 1) {
                const int lane = std::countr_zero(lanes);
                if (!(t[lane] <= ray.t_max)) continue;
                if (cull_back_faces && denominator[lane] > 0) continue;
                ray.t_max = t[lane];
                hit = Hit<Real>{t[lane], first_object_ + std::uint32_t(b * width + std::size_t(lane)), 0, 0, 0};
                found = true;
            }
        }
        return found;
    }

    bool occludes_in_blocks(const Ray<Real>& ray) const {
        for (const Block& block : blocks_) {
            alignas(64) Real t[width];
            alignas(64) Real denominator[width];
            for (std::uint32_t lanes = distances(block, ray, t, denominator); lanes != 0; lanes &= lanes - 1)
                if (t[std::countr_zero(lanes)] < ray.t_max) return true;
        }
        return false;
    }

    using Lanes = simd::Pack<Real, width>;
    struct Block {
        alignas(64) Real point[3][width] = {};
        alignas(64) Real normal[3][width] = {};
        std::uint32_t lanes = 0;  // the planes present
    };

    // PlaneShape::intersect for a block's planes, lane by lane with its operations in its order
    // (the dot products as glm sums them): bit i set where plane i is met in (t_min, ...) with a
    // t that t_max has not yet been compared with; t and the denominator (direction . normal)
    // stored. The scalar test's shortcut for planes behind the ray only skips a division whose
    // t would fail t > t_min >= 0 anyway, so every lane divides.
    PRISM_FORCE_INLINE static std::uint32_t distances(const Block& block, const Ray<Real>& ray, Real* t,
                                                          Real* denominator) {
        Lanes normal[3], along[3];
        for (int axis = 0; axis < 3; ++axis) {
            normal[axis] = Lanes::load(block.normal[axis]);
            along[axis] = Lanes::load(block.point[axis]) - Lanes::broadcast(ray.origin[axis]);
        }
        const Lanes d = (Lanes::broadcast(ray.direction.x) * normal[0] + Lanes::broadcast(ray.direction.y) * normal[1]) +
                        Lanes::broadcast(ray.direction.z) * normal[2];
        const Lanes numerator = (along[0] * normal[0] + along[1] * normal[1]) + along[2] * normal[2];
        const Lanes distance = numerator / d;
        d.store(denominator);
        distance.store(t);
        const std::uint32_t met = ((d != Lanes::broadcast(Real(0))) & (Lanes::broadcast(ray.t_min) < distance)).bits();
        return met & block.lanes;
    }

    std::uint32_t first_object_ = 0;
    std::vector<Block> blocks_;
};

}  // namespace prism
