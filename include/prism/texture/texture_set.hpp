// A scene's textures in the renderer's precision, built once: what each texture reads (image,
// Perlin noise, checkerboard) and how its value changes a surface point and its material (the
// course's decal modes, CENG795 hw4), plus the replace_background texture.
//
// Texel values (pinned against the course's hw4 scenes and expected images):
// - An 8-bit image's texel (0..255 as stored) is divided by the texture's Normalizer (default
//   255) and then, with degamma, raised to 2.2. An HDR image's texel is radiance already and is
//   used as is (no Normalizer, no degamma).
// - replace_all makes the value the point's colour, unshaded: ellipsoids_texture's left earth
//   and VeachAjar's picture (Normalizer 1, texels 0..255) show the image at its stored
//   brightness with no highlight or shadow, next to lit objects. The integrator receives it as
//   the return value of apply().
// - Perlin and checkerboard values are taken at the world-space position: cube_perlin's
//   reference shows the noise's seams on the planes y = 0 and z = 0 of the world, mid-way
//   across faces whose object-space coordinates run 0..1; the ellipsoids of ellipsoids_texture
//   (spheres scaled 5x along z) carry round, unstretched noise.
//
// Normal and bump maps perturb the current shading normal N (the interpolated one on smooth
// meshes; every course scene with maps is flat or a sphere, where the two agree) in the frame
//   T = dpdu made orthogonal to N, B = dpdv made orthogonal to N and T,
// so a mirrored (u, v) parametrisation mirrors the frame with it. Evidence, from shading the
// course's sphere scenes (no shadows) with this file and comparing with their expected images:
// - a normal map's green runs along dpdv, i.e. down the image: sphere_normal gives 32.1 dB this
//   way, 26.8 dB with green flipped (up the image);
// - bump heights differentiated per unit (u, v) with BumpFactor as given: sphere_nobump_justbump
//   shows the same relief along the coasts (29.1 dB; scaling the slope by 0.4-0.5 gave 31.0 dB,
//   within what the missing shadows and the lights' terminator explain; to re-measure with the
//   full integrator).
#pragma once

#include <prism/geometry/hit.hpp>
#include <prism/material/material.hpp>
#include <prism/math/vector.hpp>
#include <prism/scene/scene.hpp>
#include <prism/texture/checkerboard.hpp>
#include <prism/texture/mipmap.hpp>
#include <prism/texture/perlin.hpp>

#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <vector>

namespace prism {

template <Scalar Real>
class TextureSet {
public:
    TextureSet() = default;

    // Builds a pyramid only for images some trilinear texture reads, and nothing for images only
    // environment lights use.
    explicit TextureSet(const scene::Scene& scene) {
        constexpr std::size_t unused = std::numeric_limits<std::size_t>::max();
        std::vector<std::size_t> mipmap_of(scene.images.size(), unused);
        std::vector<bool> pyramid(scene.images.size(), false);
        for (const scene::Texture& texture : scene.textures)
            if (texture.kind == scene::TextureKind::image && texture.interpolation == scene::Interpolation::trilinear)
                pyramid.at(texture.image) = true;
        textures_.reserve(scene.textures.size());
        for (const scene::Texture& texture : scene.textures) {
            Entry entry;
            entry.kind = texture.kind;
            entry.decal_mode = texture.decal_mode;
            entry.interpolation = texture.interpolation;
            entry.bump_factor = Real(texture.bump_factor);
            entry.noise_conversion = texture.noise_conversion;
            entry.noise_scale = Real(texture.noise_scale);
            entry.num_octaves = texture.num_octaves;
            entry.checkerboard = {Real(texture.scale), Real(texture.offset), Vec3<Real>(texture.black_color),
                                  Vec3<Real>(texture.white_color)};
            if (texture.kind == scene::TextureKind::image) {
                const scene::TextureImage& image = scene.images.at(texture.image);
                if (mipmap_of[texture.image] == unused) {
                    mipmap_of[texture.image] = mipmaps_.size();
                    mipmaps_.emplace_back(image.pixels, pyramid[texture.image]);
                }
                entry.mipmap = mipmap_of[texture.image];
                entry.high_dynamic_range = image.high_dynamic_range;
                entry.texel_scale = image.high_dynamic_range ? Real(1) : Real(1 / texture.normalizer);
                entry.degamma = texture.degamma && !image.high_dynamic_range;
            }
            textures_.push_back(entry);
        }
        if (scene.background_texture) background_ = *scene.background_texture;
    }

    bool empty() const { return textures_.empty(); }

    // Applies the point's textures in their order in the scene file: colours go into `material`,
    // normal and bump maps into point.shading_normal (unit, on the side it was). Returns the
    // unshaded colour a replace_all texture gives the point (the last one, if several); the
    // integrator uses it as the point's radiance instead of shading.
    // `cone` sets the level of detail of trilinear textures (see MipMap::level_of_detail); the
    // default reads the finest level.
    std::optional<Vec3<Real>> apply(SurfacePoint<Real>& point, Material<Real>& material,
                                    const RayCone<Real>& cone = {}) const {
        std::optional<Vec3<Real>> unshaded;
        for (const std::uint32_t index : point.textures) {
            const Entry& texture = textures_[index];
            switch (texture.decal_mode) {
                case scene::DecalMode::replace_kd: material.diffuse = value(texture, point, cone); break;
                case scene::DecalMode::blend_kd:
                    material.diffuse = (material.diffuse + value(texture, point, cone)) / Real(2);
                    break;
                case scene::DecalMode::replace_ks: material.specular = value(texture, point, cone); break;
                case scene::DecalMode::replace_all: unshaded = value(texture, point, cone); break;
                case scene::DecalMode::replace_normal: replace_normal(texture, point, cone); break;
                case scene::DecalMode::bump_normal: bump_normal(texture, point, cone); break;
                case scene::DecalMode::replace_background: break;  // background(), for escaping rays
            }
        }
        return unshaded;
    }

    // The replace_background texture at a pixel's (u, v) = ((x + 0.5) / width, (y + 0.5) / height)
    // from the top-left corner, in the renderer's radiance units (0..255 is the PNG's range, so
    // an 8-bit image with the default Normalizer shows as stored); nothing without one.
    // The pixel's centre falls on a texel's sample point: for bilinear lookups, which sample
    // texel i at u W = i (texture/mipmap.hpp), (u, v) moves half a texel up and left, so an image
    // of the camera's resolution shows texel (x, y) at pixel (x, y), unblurred, as the course's
    // galactica_static does (its galaxy.jpg, 1280x720, bilinear: the background matches the
    // expected image exactly this way, and is blurred by half a texel without the shift).
    std::optional<Vec3<Real>> background(const Vec2<Real>& uv) const {
        if (!background_) return std::nullopt;
        const Entry& texture = textures_[*background_];
        SurfacePoint<Real> point;
        point.uv = uv;
        if (texture.kind == scene::TextureKind::image && texture.interpolation != scene::Interpolation::nearest) {
            const MipMap<Real>& image = mipmaps_[texture.mipmap];
            point.uv -= Vec2<Real>(Real(0.5) / Real(image.width()), Real(0.5) / Real(image.height()));
        }
        point.position = Vec3<Real>(uv, 0);
        const Vec3<Real> colour = value(texture, point, RayCone<Real>{});
        return texture.kind == scene::TextureKind::image && !texture.high_dynamic_range ? colour * Real(255) : colour;
    }

private:
    struct Entry {
        scene::TextureKind kind = scene::TextureKind::image;
        scene::DecalMode decal_mode = scene::DecalMode::replace_kd;
        // image
        std::size_t mipmap = 0;
        scene::Interpolation interpolation = scene::Interpolation::bilinear;
        Real texel_scale = 1;  // 1 / Normalizer for 8-bit images, 1 for HDR ones
        bool degamma = false;
        bool high_dynamic_range = false;
        Real bump_factor = 1;
        // perlin
        scene::NoiseConversion noise_conversion = scene::NoiseConversion::absval;
        Real noise_scale = 1;
        int num_octaves = 1;
        // checkerboard
        Checkerboard<Real> checkerboard;
    };

    Vec3<Real> texel(const Entry& texture, const Vec2<Real>& uv, Real level) const {
        const Vec3<Real> stored = mipmaps_[texture.mipmap].lookup(uv, level, texture.interpolation);
        const Vec3<Real> normalised = stored * texture.texel_scale;
        return texture.degamma ? glm::pow(normalised, Vec3<Real>(Real(2.2))) : normalised;
    }

    Real level_of_detail(const Entry& texture, const SurfacePoint<Real>& point, const RayCone<Real>& cone) const {
        if (texture.interpolation != scene::Interpolation::trilinear) return 0;
        return mipmaps_[texture.mipmap].level_of_detail(cone, point.dpdu, point.dpdv);
    }

    Real noise(const Entry& texture, const Vec3<Real>& position) const {
        return convert_noise(PerlinNoise<Real>::fractal(position * texture.noise_scale, texture.num_octaves),
                             texture.noise_conversion);
    }

    Vec3<Real> value(const Entry& texture, const SurfacePoint<Real>& point, const RayCone<Real>& cone) const {
        switch (texture.kind) {
            case scene::TextureKind::image: return texel(texture, point.uv, level_of_detail(texture, point, cone));
            case scene::TextureKind::perlin: return Vec3<Real>(noise(texture, point.position));
            case scene::TextureKind::checkerboard: return texture.checkerboard.colour(point.position);
        }
        return Vec3<Real>(0);
    }

    // The unit tangent frame (T, B) of the point around its shading normal; false where the
    // surface has no (u, v).
    static bool tangent_frame(const SurfacePoint<Real>& point, Vec3<Real>& tangent, Vec3<Real>& bitangent) {
        const Vec3<Real>& n = point.shading_normal;
        const Vec3<Real> t = point.dpdu - glm::dot(point.dpdu, n) * n;
        const Real t_length = glm::length(t);
        if (!(t_length > 0)) return false;
        tangent = t / t_length;
        const Vec3<Real> b = point.dpdv - glm::dot(point.dpdv, n) * n - glm::dot(point.dpdv, tangent) * tangent;
        const Real b_length = glm::length(b);
        // dpdv along dpdu (a degenerate (u, v) map): the side a right-handed (T, B, N) takes.
        bitangent = b_length > 0 ? b / b_length : glm::cross(n, tangent);
        return true;
    }

    // Takes `perturbed` as the shading normal when it leaves the surface on the side the normal
    // was on; a map that points into the surface (a texel of blue < 0.5) leaves the normal alone.
    static void set_shading_normal(SurfacePoint<Real>& point, const Vec3<Real>& perturbed) {
        const Real length = glm::length(perturbed);
        if (!(length > 0) || !(glm::dot(perturbed, point.shading_normal) > 0)) return;
        point.shading_normal = perturbed / length;
    }

    // Normal map: the texel, normalised to [0, 1], maps to [-1, 1]^3 = (x, y, z) in (T, B, N):
    //   N' = normalize(x T + y B + z N).
    // The normalised texel is not degamma'd: it holds a direction, not a colour.
    void replace_normal(const Entry& texture, SurfacePoint<Real>& point, const RayCone<Real>& cone) const {
        if (texture.kind != scene::TextureKind::image) return;
        Vec3<Real> tangent, bitangent;
        if (!tangent_frame(point, tangent, bitangent)) return;
        const Vec3<Real> stored = mipmaps_[texture.mipmap].lookup(point.uv, level_of_detail(texture, point, cone),
                                                                  texture.interpolation);
        const Vec3<Real> c = stored * texture.texel_scale * Real(2) - Real(1);
        set_shading_normal(point, c.x * tangent + c.y * bitangent + c.z * point.shading_normal);
    }

    // Bump map (Blinn 1978, as the course gives it): the surface is displaced along N by a height
    // h, so its tangents become dpdu + (dh/du) N and dpdv + (dh/dv) N, and the new normal is
    // their cross product, turned to N's side:
    //   N' ~ N + ((dh/du) (N x dpdv) + (dh/dv) (dpdu x N)) / |dpdu x dpdv|
    // (for a right-handed (dpdu, dpdv, N); a left-handed frame flips the second term's sign).
    // Images: h = BumpFactor x the normalised texel's mean of R, G, B, differentiated by forward
    // differences one texel apart (dh/du = (h(u + 1/W) - h(u)) W).
    // Perlin: h = BumpFactor x the converted noise at the world position; the surface gradient is
    // the noise gradient (forward differences in world space) minus its part along N:
    //   N' = N - BumpFactor (grad h - (grad h . N) N).
    void bump_normal(const Entry& texture, SurfacePoint<Real>& point, const RayCone<Real>& cone) const {
        const Vec3<Real> n = point.shading_normal;
        if (texture.kind == scene::TextureKind::perlin || texture.kind == scene::TextureKind::checkerboard) {
            if (texture.kind == scene::TextureKind::checkerboard) return;  // piecewise constant: no slope
            // A step small against a noise cell (1 / NoiseScale) and large against the position's
            // rounding error.
            const Real step = Real(1e-3) / std::max(texture.noise_scale, Real(1e-6)) *
                              std::max(Real(1), glm::length(point.position) * Real(1e-2));
            const Real h = noise(texture, point.position);
            const Vec3<Real> gradient =
                Vec3<Real>(noise(texture, point.position + Vec3<Real>(step, 0, 0)) - h,
                           noise(texture, point.position + Vec3<Real>(0, step, 0)) - h,
                           noise(texture, point.position + Vec3<Real>(0, 0, step)) - h) / step;
            const Vec3<Real> surface_gradient = gradient - glm::dot(gradient, n) * n;
            set_shading_normal(point, n - texture.bump_factor * surface_gradient);
            return;
        }
        const Vec3<Real> across = glm::cross(point.dpdu, point.dpdv);
        const Real area = glm::length(across);
        if (!(area > 0)) return;
        const MipMap<Real>& image = mipmaps_[texture.mipmap];
        const Real level = level_of_detail(texture, point, cone);
        const auto height = [&](const Vec2<Real>& uv) {
            const Vec3<Real> c = image.lookup(uv, level, texture.interpolation) * texture.texel_scale;
            return texture.bump_factor * (c.x + c.y + c.z) / Real(3);
        };
        const Real du = Real(1) / Real(image.width()), dv = Real(1) / Real(image.height());
        const Real h = height(point.uv);
        const Real dh_du = (height(point.uv + Vec2<Real>(du, 0)) - h) / du;
        const Real dh_dv = (height(point.uv + Vec2<Real>(0, dv)) - h) / dv;
        // The (u, v) frame may be left-handed (dpdu x dpdv = -N on the course's spheres, whose v
        // runs downwards): orient by it, so the normal tilts away from the slope either way.
        const Real side = glm::dot(across, n) < 0 ? Real(-1) : Real(1);
        const Vec3<Real> tilt = (dh_du * glm::cross(n, point.dpdv) + dh_dv * glm::cross(point.dpdu, n)) * side / area;
        set_shading_normal(point, n + tilt);
    }

    std::vector<MipMap<Real>> mipmaps_;
    std::vector<Entry> textures_;
    std::optional<std::size_t> background_;
};

}  // namespace prism
