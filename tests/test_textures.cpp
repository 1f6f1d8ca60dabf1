// Textures: mip-mapped lookups, Perlin noise, the checkerboard, and each decal mode of
// TextureSet on hand-built surface points, against values worked out by hand.
#include <prism/accel/accelerator.hpp>
#include <prism/geometry/scene_geometry.hpp>
#include <prism/image/image_io.hpp>
#include <prism/texture/texture_set.hpp>

#include <doctest/doctest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <array>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <vector>

#ifndef PRISM_SHARED_DIR
#define PRISM_SHARED_DIR "../shared"
#endif

using namespace prism;

namespace {

// A grey image whose texel (x, y) is value(x, y) in every channel.
template <class F>
Image grey_image(int width, int height, F value) {
    Image image(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) image(x, y) = glm::vec3(float(value(x, y)));
    return image;
}

// A flat, untextured point at the origin facing +z with the (u, v) frame along +x, +y.
template <Scalar Real>
SurfacePoint<Real> flat_point(const std::vector<std::uint32_t>& textures, Vec2<Real> uv = Vec2<Real>(0.5)) {
    SurfacePoint<Real> point;
    point.geometric_normal = point.shading_normal = {0, 0, 1};
    point.dpdu = {1, 0, 0};
    point.dpdv = {0, 1, 0};
    point.uv = uv;
    point.textures = textures;
    return point;
}

scene::Material grey_material() {
    scene::Material material;
    material.ambient = scene::Vec3(0.1);
    material.diffuse = scene::Vec3(0.4);
    material.specular = scene::Vec3(0.5);
    return material;
}

// A scene holding one image and one texture reading it.
scene::Scene scene_with_image_texture(Image pixels, scene::DecalMode mode, bool high_dynamic_range = false) {
    scene::Scene scene;
    scene.images.push_back({"in-code", std::make_shared<const Texels>(std::move(pixels)), high_dynamic_range});
    scene::Texture texture;
    texture.kind = scene::TextureKind::image;
    texture.decal_mode = mode;
    texture.image = 0;
    scene.textures.push_back(texture);
    return scene;
}

template <Scalar Real>
void check_vec(const Vec3<Real>& actual, const Vec3<Real>& expected, double epsilon = 1e-5) {
    CHECK(double(actual.x) == doctest::Approx(double(expected.x)).epsilon(epsilon));
    CHECK(double(actual.y) == doctest::Approx(double(expected.y)).epsilon(epsilon));
    CHECK(double(actual.z) == doctest::Approx(double(expected.z)).epsilon(epsilon));
}

}  // namespace

TEST_CASE_TEMPLATE("MipMap: nearest takes the texel containing (u, v), v = 0 at the top, repeating", Real, float, double) {
    const MipMap<Real> map(grey_image(2, 2, [](int x, int y) { return x + 2 * y; }));
    CHECK(map.nearest({0.25, 0.25}).x == 0);
    CHECK(map.nearest({0.75, 0.25}).x == 1);
    CHECK(map.nearest({0.25, 0.75}).x == 2);
    CHECK(map.nearest({0.99, 0.99}).x == 3);
    CHECK(map.nearest({1.25, 0.25}).x == 0);   // repeat
    CHECK(map.nearest({-0.25, 0.25}).x == 1);  // repeat below 0
    CHECK(map.nearest({0.25, -0.25}).x == 2);
}

TEST_CASE_TEMPLATE("MipMap: bilinear samples texel i at u W = i, the course's convention, and wraps", Real, float, double) {
    const MipMap<Real> map(grey_image(2, 2, [](int x, int y) { return x + 2 * y; }));
    CHECK(double(map.bilinear({0.0, 0.0}).x) == doctest::Approx(0.0));   // texel (0, 0) itself
    CHECK(double(map.bilinear({0.5, 0.0}).x) == doctest::Approx(1.0));   // texel (1, 0)
    CHECK(double(map.bilinear({0.5, 0.5}).x) == doctest::Approx(3.0));   // texel (1, 1)
    CHECK(double(map.bilinear({0.25, 0.0}).x) == doctest::Approx(0.5));  // u W = 0.5: (0 + 1) / 2
    CHECK(double(map.bilinear({0.375, 0.0}).x) == doctest::Approx(0.75));
    CHECK(double(map.bilinear({0.25, 0.25}).x) == doctest::Approx(1.5));  // all four
    // Not the texel centres: at u = 0.25, inside texel 0 where nearest reads 0, bilinear is
    // already half-way to texel 1.
    CHECK(map.nearest({0.25, 0.0}).x == 0);
    // The last texel blends with the first across the border (repeat): u W = 1.5.
    CHECK(double(map.bilinear({0.75, 0.0}).x) == doctest::Approx(0.5));
    CHECK(double(map.bilinear({0.0, 0.75}).x) == doctest::Approx(1.0));  // rows 1 and 0: (2 + 0) / 2
    CHECK(double(map.bilinear({-0.25, 0.0}).x) == doctest::Approx(0.5));  // u W = -0.5: texels 1 and 0
    CHECK(double(map.bilinear({1.5, 1.5}).x) == doctest::Approx(3.0));
}

TEST_CASE("scene::Texture: a texture without <Interpolation> is looked up nearest (the course's default)") {
    CHECK(scene::Texture{}.interpolation == scene::Interpolation::nearest);
}

TEST_CASE_TEMPLATE("MipMap: a 5x3 image's levels are 2x1 and 1x1 area averages", Real, float, double) {
    const MipMap<Real> map(grey_image(5, 3, [](int x, int y) { return x + 10 * y; }));
    REQUIRE(map.levels() == 3);
    CHECK(map.level(1).width == 2);
    CHECK(map.level(1).height == 1);
    CHECK(map.level(2).width == 1);
    CHECK(map.level(2).height == 1);
    // Level 1 texel 0 covers x in [0, 2.5): (0 + 1 + 2 / 2) / 2.5 = 0.8 across, rows mean 10.
    CHECK(double(map.level(1)(0, 0).x) == doctest::Approx(10.8));
    CHECK(double(map.level(1)(1, 0).x) == doctest::Approx(13.2));  // (2 / 2 + 3 + 4) / 2.5 + 10
    CHECK(double(map.level(2)(0, 0).x) == doctest::Approx(12.0));  // the image's mean
    CHECK(MipMap<Real>(grey_image(5, 3, [](int, int) { return 1; }), false).levels() == 1);
}

TEST_CASE_TEMPLATE("MipMap: trilinear blends the bilinear lookups of the two levels around it", Real, float, double) {
    const MipMap<Real> map(grey_image(5, 3, [](int x, int y) { return x + 10 * y; }));
    const Vec2<Real> uv{Real(0.2), Real(1) / Real(3)};
    // Level 0: (u W, v H) = (1, 1), texel (1, 1): 11. Level 1 (2x1): u W = 0.4 between its
    // texels 10.8 and 13.2: 10.8 + 0.4 * 2.4 = 11.76 (its single row blends with itself).
    CHECK(double(map.trilinear(uv, 0).x) == doctest::Approx(11.0));
    CHECK(double(map.trilinear(uv, Real(0.5)).x) == doctest::Approx(11.38));
    CHECK(double(map.trilinear(uv, 1).x) == doctest::Approx(11.76));
    CHECK(double(map.trilinear(uv, 7).x) == doctest::Approx(12.0));  // beyond the pyramid: 1x1
    CHECK(double(map.trilinear(uv, -3).x) == doctest::Approx(11.0));  // below 0: the image
    CHECK(double(map.trilinear(uv, std::nan("")).x) == doctest::Approx(11.0));
    CHECK(double(map.lookup(uv, 1, scene::Interpolation::bilinear).x) == doctest::Approx(11.0));  // level ignored
    CHECK(double(map.lookup(uv, 1, scene::Interpolation::trilinear).x) == doctest::Approx(11.76));
}

TEST_CASE_TEMPLATE("MipMap and TextureSet share the scene's decoded image, never copy it", Real, float, double) {
    const auto image = std::make_shared<const Image>(grey_image(4, 2, [](int x, int y) { return x + 4 * y; }));
    for (const bool pyramid : {false, true}) {
        const MipMap<Real> map(image, pyramid);
        CHECK(map.base().radiance() == image);
        CHECK(map.levels() == (pyramid ? 3 : 1));
    }
    CHECK(image.use_count() == 1);
    // Two textures reading one image: one mip map, holding the scene's pixels.
    scene::Scene scene = scene_with_image_texture(grey_image(3, 3, [](int x, int) { return x; }), scene::DecalMode::replace_kd);
    scene.textures.push_back(scene.textures[0]);
    {
        const TextureSet<Real> set(scene);
        CHECK(scene.images[0].texels.use_count() == 2);
    }
    CHECK(scene.images[0].texels.use_count() == 1);
    CHECK_THROWS_AS(MipMap<Real>(std::shared_ptr<const Image>{}), std::invalid_argument);
}

TEST_CASE_TEMPLATE("MipMap: an 8-bit image's bytes look up the bits its floats look up, on every level", Real, float, double) {
    // An odd size (37 x 23), so that every level's box filter takes partial texels.
    const int width = 37, height = 23;
    const std::size_t count = std::size_t(width) * std::size_t(height);
    auto* rgb = new std::uint8_t[3 * count];
    Image floats(width, height);
    std::mt19937 rng(7);
    for (std::size_t i = 0; i < count; ++i) {
        for (int c = 0; c < 3; ++c) rgb[3 * i + std::size_t(c)] = std::uint8_t(rng() & 0xff);
        floats.pixels[i] = glm::vec3(float(rgb[3 * i]), float(rgb[3 * i + 1]), float(rgb[3 * i + 2]));
    }
    Texels::Bytes bytes{width, height, std::shared_ptr<const std::uint8_t>(rgb, [](const std::uint8_t* held) { delete[] held; })};
    const auto from_bytes = std::make_shared<const Texels>(std::move(bytes));
    REQUIRE(from_bytes->bytes());
    CHECK(from_bytes->memory_bytes() == 3 * count);
    CHECK(from_bytes->radiance()->pixels == floats.pixels);
    const MipMap<Real> a(from_bytes), b(std::move(floats));
    REQUIRE(a.levels() == b.levels());
    for (int level = 1; level < a.levels(); ++level) CHECK(a.level(level).pixels == b.level(level).pixels);
    const auto same = [](const Vec3<Real>& x, const Vec3<Real>& y) {
        return std::bit_cast<std::array<Real, 3>>(x) == std::bit_cast<std::array<Real, 3>>(y);
    };
    int differing = 0;
    for (int i = 0; i < 2000; ++i) {
        // Coordinates beyond [0, 1) too, which repeat.
        std::uniform_real_distribution<double> uniform(-1.0, 2.0);
        const Vec2<Real> uv(Real(uniform(rng)), Real(uniform(rng)));
        const Real lod = Real(uniform(rng) * 3);
        const int level = i % a.levels();
        if (!same(a.nearest(uv, level), b.nearest(uv, level))) ++differing;
        if (!same(a.bilinear(uv, level), b.bilinear(uv, level))) ++differing;
        if (!same(a.trilinear(uv, lod), b.trilinear(uv, lod))) ++differing;
    }
    CHECK(differing == 0);
}

TEST_CASE_TEMPLATE("MipMap: the level of detail of a ray cone", Real, float, double) {
    const MipMap<Real> map(grey_image(4, 4, [](int, int) { return 0; }));
    const Vec3<Real> dpdu{1, 0, 0}, dpdv{0, 1, 0};
    // A 4x4 texture on a unit square: a footprint of 1/4 spans one texel (level 0), 1/2 two.
    CHECK(double(map.level_of_detail({Real(0.25), 1}, dpdu, dpdv)) == doctest::Approx(0.0));
    CHECK(double(map.level_of_detail({Real(0.5), 1}, dpdu, dpdv)) == doctest::Approx(1.0));
    CHECK(double(map.level_of_detail({Real(0.25), Real(0.5)}, dpdu, dpdv)) == doctest::Approx(1.0));  // grazing
    CHECK(double(map.level_of_detail({Real(0.5), 1}, dpdu * Real(2), dpdv * Real(2))) == doctest::Approx(0.0));
    CHECK(map.level_of_detail({0, 1}, dpdu, dpdv) < 0);  // a zero-width cone: the finest level
}

namespace {

// TextureSet::apply's unshaded colour as an optional, as the decal mode cases below check it.
template <Scalar Real>
std::optional<Vec3<Real>> applied(const TextureSet<Real>& set, SurfacePoint<Real>& point, Material<Real>& material) {
    Vec3<Real> unshaded(-1);
    if (set.apply(point, material, unshaded)) return unshaded;
    return std::nullopt;
}

// Perlin 2002 in its original form (fade-weighted lerps of the eight corner dot products), an
// independent check of the course's weight-product form the library uses.
double reference_noise(double x, double y, double z) {
    const auto& g = PerlinNoise<double>::gradients;
    const auto& p = PerlinNoise<double>::permutation;
    const auto phi = [&](int n) { return int(p[std::size_t(std::abs(n) % 16)]); };
    const int i = int(std::floor(x)), j = int(std::floor(y)), k = int(std::floor(z));
    const double fx = x - i, fy = y - j, fz = z - k;
    const auto fade = [](double t) { return t * t * t * (t * (t * 6 - 15) + 10); };
    const auto lerp = [](double t, double a, double b) { return a + t * (b - a); };
    const auto corner = [&](int di, int dj, int dk) {
        const auto& v = g[std::size_t(phi(i + di + phi(j + dj + phi(k + dk))))];
        return v[0] * (fx - di) + v[1] * (fy - dj) + v[2] * (fz - dk);
    };
    const double u = fade(fx), v = fade(fy), w = fade(fz);
    return lerp(w, lerp(v, lerp(u, corner(0, 0, 0), corner(1, 0, 0)), lerp(u, corner(0, 1, 0), corner(1, 1, 0))),
                lerp(v, lerp(u, corner(0, 0, 1), corner(1, 0, 1)), lerp(u, corner(0, 1, 1), corner(1, 1, 1))));
}

}  // namespace

TEST_CASE_TEMPLATE("Perlin: the course's form equals Perlin 2002's lerps, is fixed and in [-1, 1]", Real, float, double) {
    using Noise = PerlinNoise<Real>;
    CHECK(Noise::noise({3, -2, 7}) == 0);  // zero at lattice points
    const Vec3<Real> p{Real(0.3), Real(1.7), Real(-2.4)};
    CHECK(Noise::noise(p) == Noise::noise(p));
    // A value fixed by the permutation table: a change of table or formula shows here.
    CHECK(double(Noise::noise({Real(0.5), Real(0.25), Real(0.75)})) ==
          doctest::Approx(reference_noise(0.5, 0.25, 0.75)).epsilon(1e-5));
    double low = 0, high = 0;
    for (int n = 0; n < 20000; ++n) {
        const double x = -20 + 0.01373 * n, y = 5 - 0.00731 * n, z = 0.0111 * n;
        const double value = double(Noise::noise(Vec3<Real>(Vec3<double>(x, y, z))));
        CHECK(value == doctest::Approx(reference_noise(double(Real(x)), double(Real(y)), double(Real(z)))).epsilon(1e-4));
        low = std::min(low, value);
        high = std::max(high, value);
    }
    CHECK(low >= -1);
    CHECK(high <= 1);
    CHECK(low < -0.5);  // the noise spans its range, not a constant
    CHECK(high > 0.5);
}

// A high octave doubles the coordinate each time, and a far scene starts far: a cell's number past
// an int's range was converted with undefined behaviour (the sanitized build runs this test).
// The gradients depend on a number only through its sign and its remainder modulo 16.
TEST_CASE_TEMPLATE("Perlin: cells past an int's range take the gradients of their sign and remainder", Real, float, double) {
    using Noise = PerlinNoise<Real>;
    const Real y = Real(0.25), z = Real(0.75);
    for (const Real far : {Real(1e12), Real(-1e12), Real(3e15), std::ldexp(Real(1), 40) + 5, -std::ldexp(Real(1), 40) - 7}) {
        // A float or double this large is a whole number: its cell is itself, its offset 0.
        REQUIRE(std::floor(far) == far);
        const Real rest = std::fmod(std::abs(far), Real(16));
        const Real near = std::copysign(Real(1 << 20) + rest, far);  // held by an int, the same remainder and sign
        CHECK(Noise::noise({far, y, z}) == Noise::noise({near, y, z}));
        CHECK(Noise::noise({y, far, z}) == Noise::noise({y, near, z}));
        CHECK(Noise::noise({y, z, far}) == Noise::noise({y, z, near}));
    }
    // Sixty-four octaves (the loader's limit) reach 2^63 times the point: finite.
    CHECK(std::isfinite(Noise::fractal({Real(0.3), Real(0.7), Real(-0.1)}, 64)));
    // Infinity and NaN give NaN, without undefined behaviour.
    CHECK(std::isnan(Noise::noise({std::numeric_limits<Real>::infinity(), y, z})));
    CHECK(std::isnan(Noise::noise({std::numeric_limits<Real>::quiet_NaN(), y, z})));
}

TEST_CASE_TEMPLATE("Perlin: the shared weights and hashes give the corner-by-corner sum bit for bit", Real, float, double) {
    // The course's formula written corner by corner, each corner's offset, three weights and
    // hash of its own, in the same order of operations: noise() shares them between corners
    // and must change no image.
    using Noise = PerlinNoise<Real>;
    const auto corner_by_corner = [](const Vec3<Real>& p) {
        const Vec3<Real> cell = glm::floor(p);
        const int i = int(cell.x), j = int(cell.y), k = int(cell.z);
        const Vec3<Real> f = p - cell;
        const auto weight = [](Real t) {
            const Real a = std::abs(t);
            return 1 - a * a * a * (a * (a * 6 - 15) + 10);
        };
        const auto phi = [](int n) { return int(Noise::permutation[std::size_t(std::abs(n) % 16)]); };
        Real sum = 0;
        for (int corner = 0; corner < 8; ++corner) {
            const int di = corner & 1, dj = (corner >> 1) & 1, dk = (corner >> 2) & 1;
            const Vec3<Real> d = f - Vec3<Real>(Real(di), Real(dj), Real(dk));
            const auto& g = Noise::gradients[std::size_t(phi(i + di + phi(j + dj + phi(k + dk))))];
            sum += weight(d.x) * weight(d.y) * weight(d.z) * (Real(g[0]) * d.x + Real(g[1]) * d.y + Real(g[2]) * d.z);
        }
        return sum;
    };
    std::mt19937 random(3);
    std::uniform_real_distribution<double> uniform(-40, 40);
    int different = 0;
    for (int n = 0; n < 200000; ++n) {
        Vec3<Real> p(Real(uniform(random)), Real(uniform(random)), Real(uniform(random)));
        if (n % 4 == 1) p = glm::floor(p);  // on lattice points and cell faces too
        if (n % 4 == 2) p.y = std::floor(p.y);
        const Real shared = Noise::noise(p), alone = corner_by_corner(p);
        different += std::memcmp(&shared, &alone, sizeof(Real)) != 0;
    }
    CHECK(different == 0);
}

TEST_CASE_TEMPLATE("Perlin: a value and its three moved points in one pass are fractal()'s at each point, bit for bit", Real,
                   float, double) {
    // What a bump's forward differences take: the moved coordinates 10^-3 on (scaled), most in
    // the point's cell and some past its face, where the corners' gradients change.
    using Noise = PerlinNoise<Real>;
    std::mt19937 random(5);
    std::uniform_real_distribution<double> uniform(-40, 40), fraction(0, 1);
    int different = 0, crossing = 0;
    for (int n = 0; n < 100000; ++n) {
        const Real scale = Real(0.25 + 4 * fraction(random));
        Vec3<Real> p(Real(uniform(random)), Real(uniform(random)), Real(uniform(random)));
        if (n % 3 == 1) p.x = std::ceil(p.x * scale) / scale - Real(1e-4);  // just below a cell face
        const Real step = Real(1e-3);
        const int octaves = 1 + n % 4;
        const auto together = Noise::fractal_and_moved(p * scale, Vec3<Real>(p.x + step, p.y + step, p.z + step) * scale, octaves);
        const std::array<Real, 4> apart{Noise::fractal(p * scale, octaves),
                                        Noise::fractal((p + Vec3<Real>(step, 0, 0)) * scale, octaves),
                                        Noise::fractal((p + Vec3<Real>(0, step, 0)) * scale, octaves),
                                        Noise::fractal((p + Vec3<Real>(0, 0, step)) * scale, octaves)};
        different += std::memcmp(together.data(), apart.data(), sizeof apart) != 0;
        crossing += std::floor((p.x + step) * scale) != std::floor(p.x * scale);
    }
    CHECK(different == 0);
    CHECK(crossing > 10000);  // the moved point leaves the cell in many of them
}

TEST_CASE_TEMPLATE("Perlin: the course's permutation and phi(n) = P[|n| mod 16], by hand", Real, float, double) {
    using Noise = PerlinNoise<Real>;
    CHECK(Noise::permutation == std::array<std::uint8_t, 16>{4, 10, 11, 15, 14, 5, 13, 1, 6, 9, 3, 7, 8, 2, 0, 12});
    // On the lattice edge from (0, 0, 0) to (0, 1, 0) only its two ends weigh in, w(0.5) = 1/2 each:
    // n(0, 0.5, 0) = 1/4 (g_y(0, 0, 0) - g_y(0, 1, 0)).
    // g(0, 0, 0) = G[phi(0 + phi(0 + phi(0)))] = G[P[P[P[0]]]] = G[P[P[4]]] = G[P[14]] = G[0] = (1, 1, 0);
    // g(0, 1, 0) = G[phi(0 + phi(1 + 4))] = G[phi(P[5])] = G[P[5]] = G[5] = (-1, 0, 1): 1/4 (1 - 0).
    CHECK(double(Noise::noise({0, Real(0.5), 0})) == doctest::Approx(0.25));
    // At k = -1, phi(-1) = P[|-1|] = P[1] = 10 (two's complement, P[15] = 12, would give +0.25):
    // g(0, 0, -1) = G[phi(phi(10))] = G[phi(P[10] = 3)] = G[P[3]] = G[15] = (0, -1, -1);
    // g(0, 1, -1) = G[phi(phi(1 + 10))] = G[phi(P[11] = 7)] = G[P[7]] = G[1] = (-1, 1, 0): 1/4 (-1 - 1).
    CHECK(double(Noise::noise({0, Real(0.5), -1})) == doctest::Approx(-0.5));
}

TEST_CASE("Perlin: fixed values, the same in every run and build") {
    // Computed once by an independent implementation of the course's formula and table: a change
    // of table or formula shows here, and images made with the texture stay reproducible.
    CHECK(PerlinNoise<double>::noise({0.5, 0.25, 0.75}) == doctest::Approx(-0.247321128845).epsilon(1e-9));
    CHECK(PerlinNoise<double>::noise({1.3, -0.6, 2.2}) == doctest::Approx(0.103024041968).epsilon(1e-9));
    CHECK(double(PerlinNoise<float>::noise({1.3f, -0.6f, 2.2f})) == doctest::Approx(0.103024041968).epsilon(1e-4));
    CHECK(PerlinNoise<double>::noise({-0.5, 0.25, 0.75}) == doctest::Approx(-0.054866313934).epsilon(1e-9));
    // The 16-entry permutation repeats every 16 cells (at positive coordinates; |n| mirrors the
    // lattice at 0 instead).
    CHECK(PerlinNoise<double>::noise({16.5, 32.25, 48.75}) == doctest::Approx(-0.247321128845).epsilon(1e-9));
}

TEST_CASE_TEMPLATE("Perlin: octaves add noise at double frequency and half amplitude; conversions", Real, float, double) {
    using Noise = PerlinNoise<Real>;
    const Vec3<Real> p{Real(1.3), Real(0.2), Real(-0.7)};
    CHECK(Noise::fractal(p, 1) == Noise::noise(p));
    CHECK(Noise::fractal(p, 0) == Noise::noise(p));  // at least one octave
    CHECK(double(Noise::fractal(p, 3)) ==
          doctest::Approx(double(Noise::noise(p) + Noise::noise(p * Real(2)) / 2 + Noise::noise(p * Real(4)) / 4)));
    CHECK(double(convert_noise(Real(-0.4), scene::NoiseConversion::absval)) == doctest::Approx(0.4));
    CHECK(double(convert_noise(Real(-0.4), scene::NoiseConversion::linear)) == doctest::Approx(0.3));
    CHECK(double(convert_noise(Real(1), scene::NoiseConversion::linear)) == doctest::Approx(1.0));
}

TEST_CASE_TEMPLATE("Checkerboard: parity of the scaled, offset cube coordinates", Real, float, double) {
    Checkerboard<Real> board{1, 0, Vec3<Real>(Real(0.4)), Vec3<Real>(10)};
    CHECK(board.colour({Real(0.5), Real(0.5), Real(0.5)}).x == 10);  // cube (0, 0, 0): white
    CHECK(double(board.colour({Real(1.5), Real(0.5), Real(0.5)}).x) == doctest::Approx(0.4));
    CHECK(board.is_black({Real(-0.5), Real(0.5), Real(0.5)}));   // cube -1: floor, not truncation
    CHECK(!board.is_black({Real(-0.5), Real(-0.5), Real(0.5)}));
    CHECK(!board.is_black({Real(1.5), Real(1.5), Real(0.5)}));
    board.scale = 2;
    CHECK(board.is_black({Real(0.6), 0, 0}));   // floor(1.2) = 1
    CHECK(!board.is_black({Real(0.4), 0, 0}));  // floor(0.8) = 0
    board.offset = Real(0.5);
    CHECK(board.is_black({Real(0.4), 0, 0}));  // floor(1.8) + floor(1) + floor(1) = 3
}

TEST_CASE_TEMPLATE("TextureSet: replace_kd, blend_kd, replace_ks, replace_all with the Normalizer", Real, float, double) {
    Image texel = grey_image(1, 1, [](int, int) { return 0; });
    texel(0, 0) = glm::vec3(51, 102, 204);
    scene::Scene scene = scene_with_image_texture(texel, scene::DecalMode::replace_kd);
    scene.textures.push_back(scene.textures[0]);
    scene.textures[1].decal_mode = scene::DecalMode::blend_kd;
    scene.textures.push_back(scene.textures[0]);
    scene.textures[2].decal_mode = scene::DecalMode::replace_ks;
    scene.textures.push_back(scene.textures[0]);
    scene.textures[3].decal_mode = scene::DecalMode::replace_all;
    scene.textures[3].normalizer = 1;
    const TextureSet<Real> set(scene);
    const Vec3<Real> value{Real(0.2), Real(0.4), Real(0.8)};

    const std::vector<std::uint32_t> replace{0}, blend{1}, specular{2}, all{3}, replace_then_blend{0, 1};
    {
        Material<Real> material(grey_material());
        SurfacePoint<Real> point = flat_point<Real>(replace);
        CHECK(!applied(set, point, material));
        check_vec(material.diffuse, value);
        check_vec(material.specular, Vec3<Real>(Real(0.5)));
    }
    {
        Material<Real> material(grey_material());
        SurfacePoint<Real> point = flat_point<Real>(blend);
        applied(set, point, material);
        check_vec(material.diffuse, (Vec3<Real>(Real(0.4)) + value) / Real(2));
    }
    {
        Material<Real> material(grey_material());
        SurfacePoint<Real> point = flat_point<Real>(specular);
        applied(set, point, material);
        check_vec(material.specular, value);
        check_vec(material.diffuse, Vec3<Real>(Real(0.4)));
    }
    {
        Material<Real> material(grey_material());
        SurfacePoint<Real> point = flat_point<Real>(all);
        const auto unshaded = applied(set, point, material);
        REQUIRE(unshaded);
        check_vec(*unshaded, Vec3<Real>(51, 102, 204));  // Normalizer 1: the stored texel
        check_vec(material.diffuse, Vec3<Real>(Real(0.4)));
    }
    {
        // In the file's order: replace, then blend with the replaced value.
        Material<Real> material(grey_material());
        SurfacePoint<Real> point = flat_point<Real>(replace_then_blend);
        applied(set, point, material);
        check_vec(material.diffuse, value);
    }
    {
        Material<Real> material(grey_material());
        SurfacePoint<Real> point = flat_point<Real>({});
        CHECK(!applied(set, point, material));
        check_vec(material.diffuse, Vec3<Real>(Real(0.4)));
        CHECK(TextureSet<Real>(scene::Scene{}).empty());
    }
}

TEST_CASE_TEMPLATE("TextureSet: degamma after normalising; HDR texels are neither normalised nor degamma'd", Real, float, double) {
    scene::Scene scene = scene_with_image_texture(grey_image(1, 1, [](int, int) { return 51; }), scene::DecalMode::replace_kd);
    scene.textures[0].degamma = true;
    scene.images.push_back({"hdr", std::make_shared<const Texels>(grey_image(1, 1, [](int, int) { return 3; })), true});
    scene.textures.push_back(scene.textures[0]);
    scene.textures[1].image = 1;
    const TextureSet<Real> set(scene);
    const std::vector<std::uint32_t> ldr{0}, hdr{1};
    Material<Real> material(grey_material());
    SurfacePoint<Real> point = flat_point<Real>(ldr);
    applied(set, point, material);
    check_vec(material.diffuse, Vec3<Real>(Real(std::pow(0.2, 2.2))));
    point = flat_point<Real>(hdr);
    applied(set, point, material);
    check_vec(material.diffuse, Vec3<Real>(3));
}

TEST_CASE_TEMPLATE("TextureSet: replace_normal rotates the normal into the (dpdu, dpdv, N) frame", Real, float, double) {
    // (0.6, 0, 0.8) and (0, 0.6, 0.8) in [-1, 1] as texels: (c + 1) / 2 * 255.
    Image texels = grey_image(2, 1, [](int, int) { return 0; });
    texels(0, 0) = glm::vec3(1.6f, 1.0f, 1.8f) * 127.5f;
    texels(1, 0) = glm::vec3(1.0f, 1.6f, 1.8f) * 127.5f;
    scene::Scene scene = scene_with_image_texture(texels, scene::DecalMode::replace_normal);
    scene.textures[0].interpolation = scene::Interpolation::nearest;
    const TextureSet<Real> set(scene);
    const std::vector<std::uint32_t> textures{0};
    Material<Real> material(grey_material());

    SurfacePoint<Real> point = flat_point<Real>(textures, {Real(0.25), Real(0.5)});
    applied(set, point, material);
    check_vec(point.shading_normal, Vec3<Real>(Real(0.6), 0, Real(0.8)));  // red: along dpdu
    CHECK(point.geometric_normal == Vec3<Real>(0, 0, 1));

    // Green goes along dpdv, down the image (v grows downwards): sphere_normal matches the
    // course's image at 32.1 dB this way, 26.8 dB with green flipped.
    point = flat_point<Real>(textures, {Real(0.75), Real(0.5)});
    point.dpdv = {0, -3, 0};
    applied(set, point, material);
    check_vec(point.shading_normal, Vec3<Real>(0, Real(-0.6), Real(0.8)));

    // A frame on a tilted surface: T = dpdu made orthogonal to N.
    point = flat_point<Real>(textures, {Real(0.25), Real(0.5)});
    point.dpdu = {2, 0, 5};  // has a part along N, dropped
    applied(set, point, material);
    check_vec(point.shading_normal, Vec3<Real>(Real(0.6), 0, Real(0.8)));

    // No (u, v): nothing to map on.
    point = flat_point<Real>(textures, {Real(0.25), Real(0.5)});
    point.dpdu = point.dpdv = Vec3<Real>(0);
    applied(set, point, material);
    CHECK(point.shading_normal == Vec3<Real>(0, 0, 1));
}

TEST_CASE_TEMPLATE("TextureSet: bump_normal: heights in the file's units, one texel's difference per unit (u, v)", Real, float, double) {
    // A 4x1 ramp stored as 0, 1, 2, 3 (of 255): one unit of height per texel, so dh/du = 1
    // (the course's convention: the neighbour's difference, not divided by the texel's 1/4).
    scene::Scene scene = scene_with_image_texture(grey_image(4, 1, [](int x, int) { return x; }), scene::DecalMode::bump_normal);
    scene.textures[0].interpolation = scene::Interpolation::bilinear;
    const std::vector<std::uint32_t> textures{0};
    Material<Real> material(grey_material());
    {
        const TextureSet<Real> set(scene);
        SurfacePoint<Real> point = flat_point<Real>(textures, {Real(0.375), Real(0.5)});
        applied(set, point, material);
        check_vec(point.shading_normal, glm::normalize(Vec3<Real>(-1, 0, 1)));
        CHECK(double(glm::length(point.shading_normal)) == doctest::Approx(1.0));
        // Nearest: texel 1 (u W = 1.5) and texel 2: the same difference.
        scene.textures[0].interpolation = scene::Interpolation::nearest;
        point = flat_point<Real>(textures, {Real(0.375), Real(0.5)});
        applied(TextureSet<Real>(scene), point, material);
        check_vec(point.shading_normal, glm::normalize(Vec3<Real>(-1, 0, 1)));
        scene.textures[0].interpolation = scene::Interpolation::bilinear;
    }
    {
        scene.textures[0].bump_factor = 0.5;
        const TextureSet<Real> set(scene);
        SurfacePoint<Real> point = flat_point<Real>(textures, {Real(0.375), Real(0.5)});
        applied(set, point, material);
        check_vec(point.shading_normal, glm::normalize(Vec3<Real>(Real(-0.5), 0, 1)));
        // A left-handed (u, v) frame (v down the image, the course's spheres): the same slope
        // in u still tilts away from +u.
        point = flat_point<Real>(textures, {Real(0.375), Real(0.5)});
        point.dpdv = {0, -1, 0};
        applied(set, point, material);
        check_vec(point.shading_normal, glm::normalize(Vec3<Real>(Real(-0.5), 0, 1)));
        // Twice as long a tangent: half the slope per unit length.
        point = flat_point<Real>(textures, {Real(0.375), Real(0.5)});
        point.dpdu = {2, 0, 0};
        applied(set, point, material);
        check_vec(point.shading_normal, glm::normalize(Vec3<Real>(Real(-0.25), 0, 1)));
        // A mesh scaled by 1/20: heights in its own units, so a unit of height moves the point
        // by 1/20 and the tilt is 1/20 (bump_mapping_transformed's floor). Its world tangents
        // are 1/20 long too, as the geometry gives them.
        point = flat_point<Real>(textures, {Real(0.375), Real(0.5)});
        point.texture_frame = Mat3<Real>(Real(0.05));
        point.dpdu = {Real(0.05), 0, 0};
        point.dpdv = {0, Real(0.05), 0};
        applied(set, point, material);
        check_vec(point.shading_normal, glm::normalize(Vec3<Real>(Real(-0.5), 0, 1)));
        // The same tangents in world units (a sphere's): the full slope per unit length, 20 x 0.5.
        point = flat_point<Real>(textures, {Real(0.375), Real(0.5)});
        point.dpdu = {Real(0.05), 0, 0};
        point.dpdv = {0, Real(0.05), 0};
        applied(set, point, material);
        check_vec(point.shading_normal, glm::normalize(Vec3<Real>(-10, 0, 1)));
    }
    {
        // The Normalizer scales the height: 0..127.5 stored is 0..255 in the file's units.
        scene.textures[0].bump_factor = 1;
        scene.textures[0].normalizer = 127.5;
        SurfacePoint<Real> point = flat_point<Real>(textures, {Real(0.375), Real(0.5)});
        applied(TextureSet<Real>(scene), point, material);
        check_vec(point.shading_normal, glm::normalize(Vec3<Real>(-2, 0, 1)));
    }
}

TEST_CASE_TEMPLATE("SceneGeometry: textures live in a mesh's object space and in world space on spheres", Real, float, double) {
    scene::Scene world;
    world.materials.push_back(grey_material());
    // A unit square at z = 0 facing +z, scaled by 1/20 and mirrored in x.
    scene::Mesh square;
    square.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    square.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    square.triangles = {{0, 1, 2}, {0, 2, 3}};
    square.transform = glm::scale(glm::dmat4(1.0), glm::dvec3(-0.05, 0.05, 0.05));
    world.meshes.push_back(square);
    // A sphere stretched along x, far from the square.
    scene::Sphere sphere{"stretched", 0, {0, 0, 0}, 1, glm::dmat4(1.0)};
    sphere.transform = glm::translate(glm::dmat4(1.0), glm::dvec3(10, 0, 0)) * glm::scale(glm::dmat4(1.0), glm::dvec3(2, 1, 1));
    world.spheres.push_back(sphere);
    const SceneGeometry<Real, Bvh<Watertight>, false> geometry(world);
    const auto surface_at = [&](Vec3<Real> origin) {
        Ray<Real> ray{origin, Vec3<Real>(0, 0, -1), Real(0), infinity<Real>, Real(0)};
        Hit<Real> hit;
        REQUIRE(prism::closest_hit(geometry, ray, hit));
        return geometry.surface(ray, hit);
    };
    // The square, hit at world (-0.02, 0.03): object (0.4, 0.6, 0), and its transformation's
    // linear part as the frame.
    const SurfacePoint<Real> on_square = surface_at({Real(-0.02), Real(0.03), 1});
    check_vec(on_square.texture_position, Vec3<Real>(Real(0.4), Real(0.6), 0));
    CHECK(double(on_square.texture_frame[0][0]) == doctest::Approx(-0.05));
    CHECK(double(on_square.texture_frame[1][1]) == doctest::Approx(0.05));
    CHECK(double(on_square.texture_frame[2][2]) == doctest::Approx(0.05));
    // The sphere's top, world (10, 0, 1): the world position and the identity.
    const SurfacePoint<Real> on_sphere = surface_at({10, 0, 5});
    check_vec(on_sphere.texture_position, Vec3<Real>(10, 0, 1));
    CHECK(on_sphere.texture_frame == Mat3<Real>(1));
}

TEST_CASE_TEMPLATE("Mesh bump: the tangent frame from a triangle's texture coordinates, against the displaced surface by hand",
                   Real, float, double) {
    // A triangle at z = 0 facing +z, twice as long in x as its (u, v) span: with (u, v) = (0, 0),
    // (1, 0), (0, 1) at (0, 0, 0), (2, 0, 0), (0, 1, 0), dp/du = (2, 0, 0) and dp/dv = (0, 1, 0).
    // An 8x8 height image h = 10 x + 3 y (file units), BumpFactor 0.1, bilinear: one texel's step
    // changes h by 1 along u and 0.3 along v (the points below stay clear of the wrap). By hand, the displaced surface
    // q = p + h n has q_u = (2, 0, 1) and q_v = (0, 1, 0.3), so n' = q_u x q_v = (-1, -0.6, 2).
    scene::Scene world = scene_with_image_texture(grey_image(8, 8, [](int x, int y) { return 10 * x + 3 * y; }),
                                                  scene::DecalMode::bump_normal);
    world.textures[0].interpolation = scene::Interpolation::bilinear;
    world.textures[0].bump_factor = 0.1;
    world.materials.push_back(grey_material());
    scene::Mesh triangle;
    triangle.positions = {{0, 0, 0}, {2, 0, 0}, {0, 1, 0}};
    triangle.uvs = {{0, 0}, {1, 0}, {0, 1}};
    triangle.triangles = {{0, 1, 2}};
    triangle.textures = {0};
    world.meshes.push_back(triangle);
    const auto bumped_normal_at = [&](const scene::Scene& scene, Vec3<Real> origin) {
        const SceneGeometry<Real, Bvh<Watertight>, false> geometry(scene);
        Ray<Real> ray{origin, Vec3<Real>(0, 0, -1), Real(0), infinity<Real>, Real(0)};
        Hit<Real> hit;
        REQUIRE(prism::closest_hit(geometry, ray, hit));
        SurfacePoint<Real> point = geometry.surface(ray, hit);
        Material<Real> material(grey_material());
        applied(TextureSet<Real>(scene), point, material);
        return point.shading_normal;
    };
    // (u, v) = (0.375, 0.375) lies at (0.75, 0.375, 0).
    check_vec(bumped_normal_at(world, {Real(0.75), Real(0.375), 1}), glm::normalize(Vec3<Real>(-1, Real(-0.6), 2)));

    // u mirrored, as on the cube faces whose texture runs the other way: (u, v) = (1, 0), (0, 0),
    // (1, 1), so dp/du = (-2, 0, 0) and heights rising with u rise towards -x. By hand q_u =
    // (-2, 0, 1), q_v = (0, 1, 0.3), q_u x q_v = (-1, 0.6, -2), turned out of the surface:
    // (1, -0.6, 2). (u, v) = (0.625, 0.375) lies at (0.75, 0.375, 0).
    world.meshes[0].uvs = {{1, 0}, {0, 0}, {1, 1}};
    check_vec(bumped_normal_at(world, {Real(0.75), Real(0.375), 1}), glm::normalize(Vec3<Real>(1, Real(-0.6), 2)));

    // The same triangle turned a quarter about z by its transformation: the normal turns with it,
    // (x, y) -> (-y, x), and the heights stay in object units.
    world.meshes[0].uvs = {{0, 0}, {1, 0}, {0, 1}};
    world.meshes[0].transform = glm::rotate(glm::dmat4(1.0), 1.5707963267948966, glm::dvec3(0, 0, 1));
    check_vec(bumped_normal_at(world, {Real(-0.375), Real(0.75), 1}), glm::normalize(Vec3<Real>(Real(0.6), -1, 2)),
              1e-4);
}

TEST_CASE_TEMPLATE("TextureSet: Perlin colours and bumps in the texture space", Real, float, double) {
    scene::Scene scene;
    scene::Texture texture;
    texture.kind = scene::TextureKind::perlin;
    texture.noise_scale = 3;
    texture.noise_conversion = scene::NoiseConversion::linear;
    scene.textures.push_back(texture);
    texture.decal_mode = scene::DecalMode::bump_normal;
    texture.bump_factor = 0.5;
    scene.textures.push_back(texture);
    const TextureSet<Real> set(scene);
    const std::vector<std::uint32_t> colour{0}, bump{1};
    Material<Real> material(grey_material());
    SurfacePoint<Real> point = flat_point<Real>(colour);
    const Vec3<Real> p{Real(0.3), Real(0.45), Real(0.1)};
    point.texture_position = p;
    point.position = point.local_position = {7, 7, 7};  // ignored: textures read the texture space
    applied(set, point, material);
    const auto height = [&](Vec3<Real> q) { return (PerlinNoise<Real>::noise(q * Real(3)) + 1) / 2; };
    check_vec(material.diffuse, Vec3<Real>(height(p)), 1e-4);

    point.textures = bump;
    applied(set, point, material);
    const Vec3<Real> n = point.shading_normal;
    CHECK(double(glm::length(n)) == doctest::Approx(1.0));
    CHECK(n.z > 0);
    // N' = N - 0.5 (grad h)_tangent: the tilt is minus half the noise's slope along x and y.
    const Real h = Real(1e-3);
    const Real slope_x = (height(p + Vec3<Real>(h, 0, 0)) - height(p - Vec3<Real>(h, 0, 0))) / (2 * h);
    const Real slope_y = (height(p + Vec3<Real>(0, h, 0)) - height(p - Vec3<Real>(0, h, 0))) / (2 * h);
    CHECK(double(n.x / n.z) == doctest::Approx(double(-Real(0.5) * slope_x)).epsilon(0.02));
    CHECK(double(n.y / n.z) == doctest::Approx(double(-Real(0.5) * slope_y)).epsilon(0.02));

    // A mesh turned 90 degrees about z and scaled by 2: the bump is made in its object space and
    // turned with it ((x, y) -> (-y, x)); the uniform scale changes nothing (heights scale too).
    point = flat_point<Real>(bump);
    point.texture_position = p;
    point.texture_frame = Mat3<Real>(Vec3<Real>(0, 2, 0), Vec3<Real>(-2, 0, 0), Vec3<Real>(0, 0, 2));  // columns
    applied(set, point, material);
    check_vec(point.shading_normal, Vec3<Real>(-n.y, n.x, n.z), 1e-4);
}

TEST_CASE_TEMPLATE("TextureSet: Perlin bumps step 10^-3 in texture space, whatever NoiseScale", Real, float, double) {
    // NoiseScale 1000: a step of 10^-3 spans a whole noise cell, from (0, 0.5, 0) (noise 1/4, by
    // hand in the test of the course's permutation) to (1, 0.5, 0): 1/4 (g_y(1, 0, 0) - g_y(1, 1, 0))
    // = 1/4 (1 - 1) = 0; (0, 1.5, 0): 1/4 (g_y(0, 1, 0) - g_y(0, 2, 0)) = 1/4 (0 + 1) = 1/4;
    // (0, 0.5, 1): 1/4 (g_y(0, 0, 1) - g_y(0, 1, 1)) = 1/4 (-1 - 1) = -1/2.
    // Linear heights (n + 1) / 2: 0.625 at the point, 0.5, 0.625, 0.25 a step along x, y, z; the
    // gradient (-125, 0, -375), its part along the surface (-125, 0, 0), times BumpFactor 10^-3.
    scene::Scene scene;
    scene::Texture texture;
    texture.kind = scene::TextureKind::perlin;
    texture.decal_mode = scene::DecalMode::bump_normal;
    texture.noise_scale = 1000;
    texture.noise_conversion = scene::NoiseConversion::linear;
    texture.bump_factor = 1e-3;
    scene.textures.push_back(texture);
    const TextureSet<Real> set(scene);
    const std::vector<std::uint32_t> bump{0};
    Material<Real> material(grey_material());
    SurfacePoint<Real> point = flat_point<Real>(bump);
    point.texture_position = {0, Real(0.0005), 0};
    applied(set, point, material);
    check_vec(point.shading_normal, glm::normalize(Vec3<Real>(Real(0.125), 0, 1)), 1e-4);
}

TEST_CASE_TEMPLATE("TextureSet: the background texture at a pixel's (u, v)", Real, float, double) {
    CHECK(!TextureSet<Real>(scene::Scene{}).background({Real(0.5), Real(0.5)}));
    scene::Scene scene = scene_with_image_texture(grey_image(2, 2, [](int x, int y) { return 10 * x + 100 * y; }),
                                                  scene::DecalMode::replace_background);
    scene.textures[0].interpolation = scene::Interpolation::nearest;
    scene.background_texture = 0;
    const TextureSet<Real> set(scene);
    // 0..255 radiance as the PNG shows it: the default Normalizer (255) gives back the stored texel.
    check_vec(*set.background({Real(0.75), Real(0.25)}), Vec3<Real>(10));   // top right
    check_vec(*set.background({Real(0.25), Real(0.75)}), Vec3<Real>(100));  // bottom left
    {
        // Bilinear: the pixel centre lands on the texel's sample point (half a texel up and
        // left), so an image of the camera's size shows each texel on its pixel unblurred.
        scene.textures[0].interpolation = scene::Interpolation::bilinear;
        const TextureSet<Real> bilinear(scene);
        check_vec(*bilinear.background({Real(0.75), Real(0.25)}), Vec3<Real>(10));
        check_vec(*bilinear.background({Real(0.25), Real(0.75)}), Vec3<Real>(100));
        check_vec(*bilinear.background({Real(0.5), Real(0.25)}), Vec3<Real>(5));  // between two pixels
        scene.textures[0].interpolation = scene::Interpolation::nearest;
    }
    // A background texture is not applied to surfaces.
    const std::vector<std::uint32_t> textures{0};
    Material<Real> material(grey_material());
    SurfacePoint<Real> point = flat_point<Real>(textures);
    CHECK(!applied(set, point, material));
    check_vec(material.diffuse, Vec3<Real>(Real(0.4)));
}

TEST_CASE("MipMap: the course's earth.jpg keeps its mean down to 1x1") {
    const std::filesystem::path earth =
        std::filesystem::path(PRISM_SHARED_DIR) / "ceng795/hw4/2022F_Batucan2601/hw4/inputs/textures/earth.jpg";
    if (!std::filesystem::exists(earth)) {
        MESSAGE("skipped: " << earth << " is not there (course data absent)");
        return;
    }
    const MipMap<float> map(std::make_shared<const Texels>(read_texels(earth)));
    REQUIRE(map.base().bytes());  // a JPEG's texels stay bytes
    CHECK(map.width() == 1024);
    CHECK(map.height() == 512);
    CHECK(map.levels() == 11);  // 1024x512 ... 2x1, 1x1
    glm::dvec3 sum(0.0);
    const std::shared_ptr<const Image> widened = map.base().radiance();
    for (const glm::vec3& p : widened->pixels) sum += glm::dvec3(p);
    const glm::dvec3 mean = sum / double(widened->pixels.size());
    CHECK(double(map.level(10)(0, 0).x) == doctest::Approx(mean.x).epsilon(1e-4));
    CHECK(double(map.level(10)(0, 0).z) == doctest::Approx(mean.z).epsilon(1e-4));
}
