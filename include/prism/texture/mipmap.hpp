// An image texture with its mip pyramid (Williams 1983), built once: nearest, bilinear and
// trilinear lookups at (u, v) with repeat addressing, and the level of detail of a ray cone
// (Akenine-Möller et al., "Texture Level of Detail Strategies for Real-Time Ray Tracing",
// Ray Tracing Gems, ch. 20, 2019).
//
// Conventions, pinned against the course's hw4 scenes (../shared/ceng795/hw4):
// - (u, v) = (0, 0) is the top-left corner of the image, v grows downwards (row order), as the
//   course states: earth.jpg on the spheres of ellipsoids_texture and sphere_nobump_justbump
//   shows the Americas upright with the course's v = acos(y / r) / pi (v = 0 at the north pole).
// - In the continuous coordinates (x, y) = (u W, v H), nearest takes texel (floor x, floor y) and
//   bilinear blends texels (floor x, floor y) .. (floor x + 1, floor y + 1) by the fractions of x
//   and y: bilinear samples texel i at x = i, half a texel left of the square nearest gives it.
//   That is the course's formula (i = u W, p = floor(i), dx = i - p) and what its images show,
//   measured on the 2022 hw4 scenes: with texel i sampled at its centre i + 0.5 instead,
//   cube_wall gives 27.7 dB (43.4 dB as the course does), wood_box 30.1 (46.3),
//   sphere_nearest_bilinear 34.4 (53.2); nearest rounding (floor(x + 0.5)) instead of floor
//   drops sphere_nearest_bilinear to 33.8 dB and cube_cushion to 30.7.
// - A texture that names no <Interpolation> is looked up nearest (scene::Texture's default): the
//   normal maps of cube_cushion and sphere_normal name none and match the course's images at
//   59.9 and 55.0 dB nearest, 37.4 and 41.5 dB bilinear.
// - Coordinates outside [0, 1) repeat (the course's default "repeat" appearance); galactica_static's
//   TexCoordData reach -0.003 and 1.002, and a sphere's u wraps at the seam, which repeat
//   addressing blends across instead of clamping a visible line there.
#pragma once

#include <prism/image/compare.hpp>
#include <prism/image/image.hpp>
#include <prism/image/texels.hpp>
#include <prism/math/vector.hpp>
#include <prism/scene/scene.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <stdexcept>
#include <vector>

namespace prism {

// A ray cone at a hit (Ray Tracing Gems, ch. 20): its width there and |cos| of the angle between
// the ray and the surface normal, the two things the level of detail needs from the integrator.
// width 0 (the default) asks for the finest level.
template <Scalar Real>
struct RayCone {
    Real width = 0;   // distance * spread angle (+ the width the cone started with)
    Real cosine = 1;  // |dot(ray direction, normal)|
};

template <Scalar Real>
class MipMap {
public:
    // Every level halves the previous one (rounding down, at least 1 texel) by an area-weighted
    // box filter, so odd sizes (5x3 -> 2x1) keep the mean instead of dropping a row or column.
    // Without `pyramid` only the image itself is kept: nearest and bilinear textures never read
    // the other levels, and they cost a third more memory.
    // Level 0 is `texels` itself, shared with whoever else holds it (a scene's decoded texture:
    // scene::TextureImage), not copied; the coarser levels are floats.
    explicit MipMap(std::shared_ptr<const Texels> texels, bool pyramid = true) : base_(std::move(texels)) {
        if (!base_ || base_->empty()) throw std::invalid_argument("MipMap: empty image");
        const auto above_one_texel = [](const auto& level) { return level.width > 1 || level.height > 1; };
        while (pyramid && on_level(levels() - 1, above_one_texel))
            coarser_.push_back(on_level(levels() - 1, [](const auto& finer) {
                return std::make_shared<const Image>(
                    downsample_box(finer, std::max(1, finer.width / 2), std::max(1, finer.height / 2)));
            }));
    }
    explicit MipMap(std::shared_ptr<const Image> image, bool pyramid = true)
        : MipMap(image ? std::make_shared<const Texels>(std::move(image)) : nullptr, pyramid) {}
    explicit MipMap(Image image, bool pyramid = true)
        : MipMap(std::make_shared<const Image>(std::move(image)), pyramid) {}

    int levels() const { return 1 + int(coarser_.size()); }
    // Level 0: the image itself.
    const Texels& base() const { return *base_; }
    // A coarser level, 1 to levels() - 1.
    const Image& level(int index) const { return *coarser_[std::size_t(index - 1)]; }
    int width() const { return base_->width(); }
    int height() const { return base_->height(); }

    // The texel containing (u, v) on `level`.
    Vec3<Real> nearest(const Vec2<Real>& uv, int level = 0) const {
        return on_level(level, [&](const auto& image) { return nearest_in(image, uv); });
    }

    // The four texels from (floor(u W), floor(v H)) on `level`, texel i sampled at u W = i
    // (the course's convention, see the header), weighted by the distance to each.
    Vec3<Real> bilinear(const Vec2<Real>& uv, int level = 0) const {
        return on_level(level, [&](const auto& image) { return bilinear_in(image, uv); });
    }

    // Bilinear on the two levels around `level` (0 = the image itself), blended linearly; levels
    // beyond the pyramid clamp to its ends.
    Vec3<Real> trilinear(const Vec2<Real>& uv, Real level) const {
        const Real last = Real(levels() - 1);
        if (!(level > 0)) return bilinear(uv, 0);  // also NaN, from a zero-area tangent frame
        if (level >= last) return bilinear(uv, levels() - 1);
        const int finer = int(level);
        const Real t = level - Real(finer);
        return (1 - t) * bilinear(uv, finer) + t * bilinear(uv, finer + 1);
    }

    // The lookup a texture declares. Nearest and bilinear read the image itself, as the course
    // defines them; only trilinear uses the level of detail.
    Vec3<Real> lookup(const Vec2<Real>& uv, Real level, scene::Interpolation interpolation) const {
        switch (interpolation) {
            case scene::Interpolation::nearest: return nearest(uv);
            case scene::Interpolation::bilinear: return bilinear(uv);
            case scene::Interpolation::trilinear: return trilinear(uv, level);
        }
        return bilinear(uv);
    }

    // The level of detail of a ray cone on a surface whose position changes by dpdu, dpdv per
    // unit (u, v) (Ray Tracing Gems ch. 20, eq. 34 with the triangle's texel-to-world area ratio
    // taken from the tangents): log2 of the texels the cone's footprint spans along one side,
    //   lambda = 0.5 log2(W H / |dpdu x dpdv|) + log2(width / cosine).
    // -infinity (the finest level) for a zero-width cone; NaN for a surface without (u, v),
    // which trilinear() treats as the finest level too.
    Real level_of_detail(const RayCone<Real>& cone, const Vec3<Real>& dpdu, const Vec3<Real>& dpdv) const {
        const Real texels_per_area = Real(width()) * Real(height()) / glm::length(glm::cross(dpdu, dpdv));
        return Real(0.5) * std::log2(texels_per_area) + std::log2(cone.width / std::max(cone.cosine, Real(1e-4)));
    }

private:
    // `read(image)` on level `level`'s storage (the base's bytes or floats, or a coarser level).
    template <class Read>
    decltype(auto) on_level(int level, Read&& read) const {
        return level == 0 ? base_->visit(read) : read(*coarser_[std::size_t(level - 1)]);
    }

    template <class Texels2D>
    static Vec3<Real> nearest_in(const Texels2D& image, const Vec2<Real>& uv) {
        const int x = repeat_index(int(std::floor(uv.x * Real(image.width))), image.width);
        const int y = repeat_index(int(std::floor(uv.y * Real(image.height))), image.height);
        return Vec3<Real>(image(x, y));
    }

    template <class Texels2D>
    static Vec3<Real> bilinear_in(const Texels2D& image, const Vec2<Real>& uv) {
        const Real x = uv.x * Real(image.width);
        const Real y = uv.y * Real(image.height);
        const Real x_floor = std::floor(x), y_floor = std::floor(y);
        const Real fx = x - x_floor, fy = y - y_floor;
        const int x0 = repeat_index(int(x_floor), image.width), x1 = repeat_next(x0, image.width);
        const int y0 = repeat_index(int(y_floor), image.height), y1 = repeat_next(y0, image.height);
        const Vec3<Real> top = (1 - fx) * Vec3<Real>(image(x0, y0)) + fx * Vec3<Real>(image(x1, y0));
        const Vec3<Real> bottom = (1 - fx) * Vec3<Real>(image(x0, y1)) + fx * Vec3<Real>(image(x1, y1));
        return (1 - fy) * top + fy * bottom;
    }

    std::shared_ptr<const Texels> base_;
    std::vector<std::shared_ptr<const Image>> coarser_;  // levels 1, 2, ...
};

}  // namespace prism
