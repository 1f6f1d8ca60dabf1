// A scene's textures in the renderer's precision, built once: what each texture reads (image,
// Perlin noise, checkerboard) and how its value changes a surface point and its material (the
// course's decal modes, CENG795 hw4), plus the replace_background texture.
//
// Texel values (pinned against the course's hw4 scenes and expected images):
// - An 8-bit image's texel (0..255 as stored) is divided by the texture's Normalizer (default
//   255) and then, with degamma, raised to 2.2. For replace_ks this makes ks the texel / 255:
//   wood_box 46.3 dB; 22.5 dB without its specular map, 42.1 dB with a Normalizer of 510. An HDR image's texel is radiance already and is
//   used as is (no Normalizer, no degamma).
// - replace_all makes the value the point's colour, unshaded: ellipsoids_texture's left earth
//   and VeachAjar's picture (Normalizer 1, texels 0..255) show the image at its stored
//   brightness with no highlight or shadow, next to lit objects. The integrator receives it
//   from apply().
// - Perlin and checkerboard values are taken in the texture space of SurfacePoint
//   (geometry/hit.hpp): a mesh's object space, world space on spheres and planes. With the
//   course's noise table (texture/perlin.hpp), cube_perlin (two transformed cube meshes) renders
//   at 80.2 dB in object space and 21.0 dB in world space, while ellipsoids_texture (spheres
//   scaled 5x along z, round noise) renders at 51.4 dB in world space and 25.6 dB in object
//   space. The checkerboard follows the same rule unmeasured (no course image shows one).
//
// Normal and bump maps perturb the current shading normal N (the interpolated one on smooth
// meshes; every course scene with maps is flat or a sphere, where the two agree) in the frame
//   T = dpdu made orthogonal to N, B = dpdv made orthogonal to N and T,
// so a mirrored (u, v) parametrisation mirrors the frame with it. Evidence, from the course's
// expected images:
// - a normal map's green runs along dpdv, i.e. down the image: shading sphere_normal without
//   shadows gave 32.1 dB this way, 26.8 dB with green flipped (up the image); the full
//   integrator with nearest lookups (its map names no Interpolation) gives 55.0 dB;
// - image bump heights are in the 8-bit file's units (BumpFactor x the texel's mean of R, G, B
//   x 255 / Normalizer), and the difference between neighbouring texels is taken as the
//   derivative per unit of u or v (not divided by the texel's 1/W). Measured with the full
//   integrator: galactica_static 52.0 dB, sphere_nobump_bump 50.2, sphere_nobump_justbump 48.7;
//   the same heights differentiated per unit (u, v) (times W, H) gave 38.4, 33.5 and 30.8 dB:
//   255 / W = 0.25 along the earth's u (1024 texels), 255 / H = 0.5 along its v and rap01's
//   (512), the factors a per-axis fit found (0.25, 0.5: 50.2 and 48.6 dB on the spheres).
// - heights are measured in the same texture space: a mesh's own units, world units on spheres.
//   bump_mapping_transformed (a plane scaled by 0.05, a sphere scaled by (-2, 1, 1)): 45.5 dB;
//   both in world units 21.0 dB (the plane's bumps 20 times too steep); both in object units
//   34.6 dB (30.0 dB inside the sphere's outline, 41.5 dB with the sphere in world units).
// - the alternatives, measured (prism-suite, full integrator) against the shared hw4 images
//   sphere_nobump_bump / sphere_nobump_justbump / galactica_static / bump_mapping_transformed:
//   mean of R, G, B 50.2 / 48.7 / 54.6 / 45.5 dB (galactica 52.0 before camera rays skipped
//   flat back faces); Rec. 709 luminance 40.6 / 44.1 / 54.2 / 45.3; the red channel
//   39.0 / 40.1 / 51.4 / 45.0; the largest channel 37.9 / 40.2 / 51.7 / 45.0; central
//   differences 34.4 / 32.8 / 40.6 / 27.1; unit tangents in place of dpdu, dpdv (a tilt of
//   BumpFactor x the difference whatever the surface's size) 28.1 / 19.6 / 28.4 / 14.4; one sign
//   for every frame (ignoring its handedness) 50.2 / 48.7 / 33.9 / 45.5 with the left-handed
//   frames' sign, 29.6 / 24.5 / 44.6 / 45.5 with the right-handed ones' (galactica's triangles
//   have both: 1477 right-handed, 1359 left-handed). The shared bump surfaces have long
//   tangents: |dpdu|, |dpdv| average 19 and 38 texture-space units per unit (u, v) on galactica,
//   53 and 31 on the spheres; a unit cube face with (u, v) over [0, 1] has 1 and 1, so its bumps
//   tilt 19 times more than any shared image shows, a range no shared image tests.
// - Perlin bumps differentiate the noise 10^-3 apart in that space, whatever NoiseScale:
//   cube_perlin_bump 75.2 dB, sphere_perlin_bump 50.0 dB; 10^-3 / NoiseScale apart (10^-4 on the
//   cube) gives 39.1 and 50.0 dB, 10^-2 / NoiseScale 75.2 and 40.8 dB.
#pragma once

#include <prism/math/force_inline.hpp>
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
                    mipmaps_.emplace_back(image.texels, pyramid[texture.image]);
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
    // normal and bump maps into point.shading_normal (unit, on the side it was). Returns whether
    // a replace_all texture gives the point its colour, unshaded (the last one, if several),
    // written to `unshaded`; the integrator uses it as the point's radiance instead of shading.
    // `cone` sets the level of detail of trilinear textures (see MipMap::level_of_detail); the
    // default reads the finest level.
    // A point without textures returns at once, inlined into the integrator: out of line, the
    // call alone (its frame set up for the texture lookups) was 3.3-3.9% of hw7 path_diffuse's
    // and path_glass's time, scenes with no texture at all. The colour is written to an
    // argument rather than returned as a std::optional: the optional of a point without
    // textures was stored in part (its flag) and then read whole, a read that waits for the
    // store to reach the cache (store forwarding fails): 15% of the path tracer's trace.
    PRISM_FORCE_INLINE bool apply(SurfacePoint<Real>& point, Material<Real>& material, Vec3<Real>& unshaded,
                                  const RayCone<Real>& cone = {}) const {
        if (point.textures.empty()) return false;
        return apply_textures(point, material, unshaded, cone);
    }

private:
    bool apply_textures(SurfacePoint<Real>& point, Material<Real>& material, Vec3<Real>& unshaded,
                        const RayCone<Real>& cone) const {
        bool replaced = false;
        for (const std::uint32_t index : point.textures) {
            const Entry& texture = textures_[index];
            switch (texture.decal_mode) {
                case scene::DecalMode::replace_kd: material.diffuse = value(texture, point, cone); break;
                case scene::DecalMode::blend_kd:
                    material.diffuse = (material.diffuse + value(texture, point, cone)) / Real(2);
                    break;
                case scene::DecalMode::replace_ks: material.specular = value(texture, point, cone); break;
                case scene::DecalMode::replace_all:
                    unshaded = value(texture, point, cone);
                    replaced = true;
                    break;
                case scene::DecalMode::replace_normal: replace_normal(texture, point, cone); break;
                case scene::DecalMode::bump_normal: bump_normal(texture, point, cone); break;
                case scene::DecalMode::replace_background: break;  // background(), for escaping rays
            }
        }
        return replaced;
    }

public:
    // The replace_background texture at a pixel's (u, v) = ((x + 0.5) / width, (y + 0.5) / height)
    // from the top-left corner, in the renderer's radiance units (0..255 is the PNG's range, so
    // an 8-bit image with the default Normalizer shows as stored); nothing without one.
    // The pixel's centre falls on a texel's sample point: for bilinear lookups, which sample
    // texel i at u W = i (texture/mipmap.hpp), (u, v) moves half a texel up and left, so an image
    // of the camera's resolution shows texel (x, y) at pixel (x, y), unblurred, as the course's
    // galactica_static does (its galaxy.jpg, 1280x720, bilinear: the background, 61% of the
    // image, is within one level of the expected image this way, 98% of it identical, and is
    // blurred by half a texel without the shift).
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
            case scene::TextureKind::perlin: return Vec3<Real>(noise(texture, point.texture_position));
            case scene::TextureKind::checkerboard: return texture.checkerboard.colour(point.texture_position);
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

    // Bump map (Blinn 1978, as the course gives it): the surface is displaced along its normal by
    // a height h, so its tangents become dpdu + (dh/du) d and dpdv + (dh/dv) d, and the new normal
    // is their cross product, turned to N's side:
    //   N' ~ N + ((dh/du) (d x dpdv) + (dh/dv) (dpdu x d)) / |dpdu x dpdv|
    // (for a right-handed (dpdu, dpdv, N); a left-handed frame flips the second term's sign).
    // d is where a unit of height moves the point in world space: N itself in world space, the
    // object's unit normal carried by the mesh's transformation in a mesh's object space
    // (SurfacePoint::texture_frame), so a scaled mesh scales its bumps with it.
    // Images: h = BumpFactor x the mean of R, G, B in the file's 0..255 units (x 255 / Normalizer),
    // and dh/du is the forward difference one texel apart, h(u + 1/W) - h(u), taken per unit u as
    // the course does (see the header).
    // Perlin: h = BumpFactor x the converted noise at the texture-space position; its gradient by
    // forward differences 10^-3 apart in that space, less its part along the normal n there:
    //   n' = n - BumpFactor (grad h - (grad h . n) n), carried to world space as normals are.
    void bump_normal(const Entry& texture, SurfacePoint<Real>& point, const RayCone<Real>& cone) const {
        if (texture.kind == scene::TextureKind::checkerboard) return;  // piecewise constant: no slope
        const Vec3<Real> n = point.shading_normal;
        const Mat3<Real>& frame = point.texture_frame;
        // The unit normal in texture space: normals map by the inverse transpose, so back by the transpose.
        const Vec3<Real> texture_normal = glm::normalize(glm::transpose(frame) * n);
        if (texture.kind == scene::TextureKind::perlin) {
            const Real step = Real(1e-3);
            const Vec3<Real>& p = point.texture_position;
            // noise() at p and at p + step along each axis, in one pass over the octaves: the
            // moved point's other coordinates are p's (p.y + 0 and p.y reach the same cell and
            // offset, signed zeros included).
            const auto values = PerlinNoise<Real>::fractal_and_moved(
                p * texture.noise_scale,
                Vec3<Real>(p.x + step, p.y + step, p.z + step) * texture.noise_scale, texture.num_octaves);
            const auto converted = [&](std::size_t k) { return convert_noise(values[k], texture.noise_conversion); };
            const Real h = converted(0);
            const Vec3<Real> gradient = Vec3<Real>(converted(1) - h, converted(2) - h, converted(3) - h) / step;
            const Vec3<Real> surface_gradient = gradient - glm::dot(gradient, texture_normal) * texture_normal;
            const Vec3<Real> bumped = texture_normal - texture.bump_factor * surface_gradient;
            set_shading_normal(point, glm::transpose(glm::inverse(frame)) * bumped);
            return;
        }
        const Vec3<Real> across = glm::cross(point.dpdu, point.dpdv);
        const Real area = glm::length(across);
        if (!(area > 0)) return;
        const MipMap<Real>& image = mipmaps_[texture.mipmap];
        const Real level = level_of_detail(texture, point, cone);
        const auto height = [&](const Vec2<Real>& uv) {
            const Vec3<Real> c = image.lookup(uv, level, texture.interpolation) * (texture.texel_scale * Real(255));
            return texture.bump_factor * (c.x + c.y + c.z) / Real(3);
        };
        const Real h = height(point.uv);
        const Real dh_du = height(point.uv + Vec2<Real>(Real(1) / Real(image.width()), 0)) - h;
        const Real dh_dv = height(point.uv + Vec2<Real>(0, Real(1) / Real(image.height()))) - h;
        const Vec3<Real> d = frame * texture_normal;
        // The (u, v) frame may be left-handed (dpdu x dpdv = -N on the course's spheres, whose v
        // runs downwards): orient by it, so the normal tilts away from the slope either way.
        const Real side = glm::dot(across, n) < 0 ? Real(-1) : Real(1);
        const Vec3<Real> tilt = (dh_du * glm::cross(d, point.dpdv) + dh_dv * glm::cross(point.dpdu, d)) * side / area;
        set_shading_normal(point, n + tilt);
    }

    std::vector<MipMap<Real>> mipmaps_;
    std::vector<Entry> textures_;
    std::optional<std::size_t> background_;
};

}  // namespace prism
