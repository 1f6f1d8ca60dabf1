// The environment light (the course's SphericalDirectionalLight): its two mappings against the
// course's formulas, the piecewise-constant distributions it samples, a white furnace for each
// sampling strategy, the same sky in both layouts, the shared envmaps (every file reads; the
// Uffizi lat-long and its derived probe agree; importance sampling tames Venice's sun), and the
// prism-envmap command.
#include "chi_square.hpp"
#include "temporary_folder.hpp"

#include <prism/image/image_io.hpp>
#include <prism/image/tonemap.hpp>
#include <prism/light/environment_light.hpp>
#include <prism/light/light_set.hpp>
#include <prism/light/point_light.hpp>
#include <prism/light/procedural_sky.hpp>
#include <prism/sampling/piecewise_constant.hpp>
#include <prism/sampling/random.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <sys/wait.h>

namespace {

namespace fs = std::filesystem;
namespace scene = prism::scene;
using prism::Vec2;
using prism::Vec3;
using Layout = scene::EnvironmentLayout;
using Sampling = scene::EnvironmentSampling;
using prism_test::pearson_chi_square;

using std::numbers::pi;

static_assert(prism::Light<prism::EnvironmentLight<float>, float>);
static_assert(prism::Light<prism::EnvironmentLight<double>, double>);

fs::path shared_envmaps() { return fs::path(PRISM_SHARED_DIR) / "envmaps"; }

// Directions spread evenly over the sphere (the Fibonacci lattice), the same for every run.
std::vector<glm::dvec3> sphere_directions(int count) {
    std::vector<glm::dvec3> directions;
    const double golden_angle = pi * (3 - std::sqrt(5.0));
    for (int i = 0; i < count; ++i) {
        const double y = 1 - (i + 0.5) * 2 / count;
        const double radius = std::sqrt(1 - y * y);
        directions.emplace_back(radius * std::cos(golden_angle * i), y, radius * std::sin(golden_angle * i));
    }
    return directions;
}

template <class Real>
prism::EnvironmentMap<Real> map_of(prism::Image image, Layout layout) {
    return prism::EnvironmentMap<Real>(std::make_shared<const prism::Image>(std::move(image)), layout);
}

prism::Image filled(int width, int height, glm::vec3 value) {
    prism::Image image(width, height);
    std::fill(image.pixels.begin(), image.pixels.end(), value);
    return image;
}

// The mean of the course's diffuse term kd cos(theta) sample.radiance over `count` samples, as
// the integrator computes it (samples below the surface count as zero), and its variance.
struct Estimate {
    glm::dvec3 mean{0.0};
    double luminance_variance = 0;
};

template <class Real>
Estimate diffuse_estimate(const prism::EnvironmentLight<Real>& light, const Vec3<Real>& normal, int count,
                          std::uint64_t seed = 7) {
    prism::Random random(seed);
    const prism::ShadingFrame<Real> at{Vec3<Real>(0), normal};
    glm::dvec3 sum(0.0);
    double sum_y = 0, sum_y2 = 0;
    for (int i = 0; i < count; ++i) {
        const prism::LightSample<Real> sample = light.sample(at, random.uniform2<Real>());
        const double cos_theta = double(glm::dot(normal, sample.direction));
        if (cos_theta <= 0) continue;
        const glm::dvec3 value = cos_theta * glm::dvec3(sample.radiance);
        sum += value;
        const double y = prism::luminance(value);
        sum_y += y;
        sum_y2 += y * y;
    }
    const double mean_y = sum_y / count;
    return {sum / double(count), sum_y2 / count - mean_y * mean_y};
}

// Where the course puts -Z, +X, -X, +Y and -Y in the image (a NaN u: any u, at a pole), then
// direction -> (u, v) -> direction over the sphere, except within 2.6 degrees of +Z (the
// probe squeezes those into its rim, where float cannot bring them back).
template <class Real, class ToImage, class ToDirection>
void check_mapping(ToImage to_image, ToDirection to_direction, const Vec2<Real> (&expected)[5]) {
    const Real tolerance = std::is_same_v<Real, float> ? Real(1e-5) : Real(1e-12);
    const Vec3<Real> axes[5] = {{0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
    for (int i = 0; i < 5; ++i) {
        CAPTURE(axes[i]);
        const Vec2<Real> uv = to_image(axes[i]);
        if (!std::isnan(expected[i].x)) CHECK(uv.x == doctest::Approx(expected[i].x).epsilon(tolerance));
        CHECK(uv.y == doctest::Approx(expected[i].y).epsilon(tolerance));
    }
    for (const glm::dvec3& d : sphere_directions(2000)) {
        const Vec3<Real> direction(d);
        if (direction.z > Real(0.999)) continue;
        CHECK(glm::length(to_direction(to_image(direction)) - direction) < 50 * tolerance);
    }
}

}  // namespace

TEST_CASE_TEMPLATE("lat-long mapping: the course's axes and round trips", Real, float, double) {
    // u = (1 + atan2(x, -z) / pi) / 2, v = acos(y) / pi: -Z in the middle, +X at 3/4, +Y on top.
    const Real any = std::numeric_limits<Real>::quiet_NaN();
    const Vec2<Real> expected[5] = {{0.5, 0.5}, {0.75, 0.5}, {0.25, 0.5}, {any, 0}, {any, 1}};
    check_mapping<Real>([](const Vec3<Real>& d) { return prism::latlong_coordinates(d); },
                        [](const Vec2<Real>& uv) { return prism::latlong_direction(uv); }, expected);
    // +Z is the seam: u = 1 from the +X side, u = 0 from the -X side.
    CHECK(prism::latlong_coordinates(Vec3<Real>(0, 0, 1)).x == doctest::Approx(1));
    CHECK(prism::latlong_coordinates(Vec3<Real>(-1e-6, 0, 1)).x < Real(0.01));
    CHECK(prism::latlong_coordinates(Vec3<Real>(0, 0, 1)).y == doctest::Approx(0.5));
}

TEST_CASE_TEMPLATE("lookup: bilinear between pixel centres, lat-long columns wrap, rows and probes clamp", Real, float,
                   double) {
    // A 4x2 map whose pixel (x, y) holds x + 10 y: a blend of columns shows where u landed.
    prism::Image image(4, 2);
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) image(x, y) = glm::vec3(float(x + 10 * y));
    const auto shared = std::make_shared<const prism::Image>(image);
    const prism::EnvironmentMap<Real> latlong(shared, Layout::latlong), probe(shared, Layout::probe);
    const auto at = [](const prism::EnvironmentMap<Real>& map, double u, double v) {
        return double(map.lookup(Vec2<Real>(Real(u), Real(v))).x);
    };
    // Pixel centres: u = (x + 0.5) / 4, v = (y + 0.5) / 2.
    CHECK(at(latlong, 0.375, 0.25) == doctest::Approx(1));
    CHECK(at(latlong, 0.5, 0.25) == doctest::Approx(1.5));
    // Left of the first centre, a lat-long map blends the last column with the first (one
    // meridian); a probe clamps to its first column.
    CHECK(at(latlong, 0.0, 0.25) == doctest::Approx(1.5));     // (3 + 0) / 2
    CHECK(at(latlong, 0.0625, 0.25) == doctest::Approx(0.75)); // 3 / 4 + 0
    CHECK(at(probe, 0.0, 0.25) == doctest::Approx(0));
    // Right of the last centre the same way round, and u past 1 goes on around.
    CHECK(at(latlong, 1.0, 0.25) == doctest::Approx(1.5));
    CHECK(at(latlong, 1.125, 0.25) == doctest::Approx(at(latlong, 0.125, 0.25)));
    CHECK(at(latlong, -0.875, 0.75) == doctest::Approx(at(latlong, 0.125, 0.75)));
    CHECK(at(probe, 1.0, 0.25) == doctest::Approx(3));
    // Rows clamp in both layouts: above the first centre is the first row.
    CHECK(at(latlong, 0.375, 0.0) == doctest::Approx(1));
    CHECK(at(latlong, 0.375, 1.0) == doctest::Approx(11));
    CHECK(at(probe, 0.375, 0.5) == doctest::Approx(6));
}

TEST_CASE("repeat_index and repeat_next: the remainder's wrap, with or without the division") {
    for (const int size : {1, 2, 3, 7, 512}) {
        for (int index = -3 * size - 2; index <= 3 * size + 2; ++index) {
            const int expected = ((index % size) + size) % size;
            CHECK(prism::repeat_index(index, size) == expected);
            if (index >= 0 && index < size) CHECK(prism::repeat_next(index, size) == ((index + 1) % size));
        }
    }
    CHECK(prism::repeat_index(std::numeric_limits<int>::min(), 7) == ((std::numeric_limits<int>::min() % 7) + 7) % 7);
    CHECK(prism::repeat_index(std::numeric_limits<int>::max(), 7) == std::numeric_limits<int>::max() % 7);
}

TEST_CASE_TEMPLATE("probe mapping: the course's axes and round trips", Real, float, double) {
    // Centre -Z, right +X, up +Y; radius proportional to the angle from -Z, so the axes at 90
    // degrees sit halfway to the rim.
    const Vec2<Real> expected[5] = {{0.5, 0.5}, {0.75, 0.5}, {0.25, 0.5}, {0.5, 0.25}, {0.5, 0.75}};
    check_mapping<Real>([](const Vec3<Real>& d) { return prism::probe_coordinates(d); },
                        [](const Vec2<Real>& uv) { return prism::probe_direction(uv); }, expected);
    // +Z is the rim, from whichever side it is approached.
    for (const Vec3<Real>& near_back : {Vec3<Real>(0, 0, 1), glm::normalize(Vec3<Real>(1e-4, 0, 1)),
                                        glm::normalize(Vec3<Real>(0, -1e-4, 1)), glm::normalize(Vec3<Real>(-1e-4, 1e-4, 1))}) {
        const Vec2<Real> uv = prism::probe_coordinates(near_back);
        CHECK(glm::length(Real(2) * uv - Vec2<Real>(1)) == doctest::Approx(1).epsilon(1e-3));
    }
}

TEST_CASE_TEMPLATE("the layouts' Jacobians integrate to the sphere's 4 pi", Real, float, double) {
    // Midpoint rule over the unit square: J is the solid angle per unit of image area.
    const int n = 1024;
    double latlong = 0, probe = 0;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const Vec2<Real> uv((Real(x) + Real(0.5)) / Real(n), (Real(y) + Real(0.5)) / Real(n));
            latlong += double(prism::latlong_jacobian(uv));
            probe += double(prism::probe_jacobian(uv));
        }
    CHECK(latlong / (double(n) * n) == doctest::Approx(4 * pi).epsilon(1e-4));
    CHECK(probe / (double(n) * n) == doctest::Approx(4 * pi).epsilon(2e-3));  // the rim cuts pixels
    // And J matches the mapping: a small square of image maps to J times its area in directions.
    for (const Vec2<Real> uv : {Vec2<Real>(0.3, 0.2), Vec2<Real>(0.62, 0.71), Vec2<Real>(0.5, 0.5)}) {
        const double h = 1e-3;
        for (const Layout layout : {Layout::latlong, Layout::probe}) {
            auto direction = [&](double du, double dv) {
                const glm::dvec2 p(double(uv.x) + du, double(uv.y) + dv);
                return layout == Layout::latlong ? prism::latlong_direction(p) : prism::probe_direction(p);
            };
            const double area = glm::length(glm::cross(direction(h, 0) - direction(-h, 0), direction(0, h) - direction(0, -h))) / (4 * h * h);
            const double jacobian = layout == Layout::latlong ? double(prism::latlong_jacobian(uv)) : double(prism::probe_jacobian(uv));
            CHECK(area == doctest::Approx(jacobian).epsilon(1e-3));
        }
    }
}

TEST_CASE_TEMPLATE("piecewise-constant 1D: density, frequencies and the inverse CDF", Real, float, double) {
    const std::vector<Real> table = {1, 0, 3, 0.5, 0, 2.5, 1};  // zeros must never be drawn
    const prism::PiecewiseConstant1D<Real> distribution(table);
    const double total = 8.0;
    CHECK(distribution.integral() == doctest::Approx(total / 7));

    // The density integrates to 1 over [0, 1).
    double integral = 0;
    const int steps = 7000;
    for (int i = 0; i < steps; ++i) integral += double(distribution.pdf((Real(i) + Real(0.5)) / Real(steps))) / steps;
    CHECK(integral == doctest::Approx(1).epsilon(1e-5));

    // Frequencies: chi-square with 4 degrees of freedom (5 non-zero cells); 18.5 is its 99.9%
    // quantile, so a correct sampler fails once in a thousand seeds and this seed is fixed.
    prism::Random random(11);
    const int count = 200000;
    std::vector<int> hits(table.size(), 0);
    for (int i = 0; i < count; ++i) {
        const Real u = random.uniform<Real>();
        const auto sample = distribution.sample(u);
        ++hits[sample.cell];
        REQUIRE(sample.x >= 0);
        REQUIRE(sample.x < 1);
        CHECK(sample.pdf == doctest::Approx(double(distribution.pdf(sample.x))));
        CHECK(double(distribution.cdf(sample.x)) == doctest::Approx(double(u)).epsilon(1e-5));  // inverse of sample()
    }
    const double chi_square = pearson_chi_square(table, hits, count);
    CHECK(chi_square < 18.5);

    // A table of zeros becomes uniform instead of dividing by zero.
    const prism::PiecewiseConstant1D<Real> zeros(std::vector<Real>(4, Real(0)));
    CHECK(zeros.sample(Real(0.6)).x == doctest::Approx(0.6));
    CHECK(zeros.pdf(Real(0.3)) == doctest::Approx(1));
}

TEST_CASE_TEMPLATE("piecewise-constant 1D: the guided search finds std::upper_bound's cell for every u", Real, float,
                   double) {
    // Tables with runs of zero cells and one cell far brighter than the rest (many cells under
    // one guide, guides with no cell of their own), of sizes that are not all multiples of the
    // four cells a guide covers.
    for (const std::size_t n : {std::size_t(1), std::size_t(5), std::size_t(64), std::size_t(1023)}) {
        CAPTURE(n);
        prism::Random random(n);
        std::vector<Real> table(n);
        for (std::size_t i = 0; i < n; ++i) table[i] = (i % 7 == 3 || i % 11 < 4) ? Real(0) : random.uniform<Real>();
        table[n / 2] = n > 1 ? Real(1e4) : Real(1);
        const prism::PiecewiseConstant1D<Real> distribution(table);

        // The CDF as the constructor builds it, searched the plain way.
        std::vector<double> running(n + 1, 0.0);
        for (std::size_t i = 0; i < n; ++i) running[i + 1] = running[i] + double(table[i]) / double(n);
        std::vector<Real> cdf(n + 1);
        for (std::size_t i = 0; i <= n; ++i) cdf[i] = Real(running[i] / running[n]);
        cdf[n] = 1;
        const auto plain_cell = [&](Real u) {
            const std::ptrdiff_t above = std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin();
            return std::min(std::size_t(std::max<std::ptrdiff_t>(above - 1, 0)), n - 1);
        };

        // Every CDF value and its neighbours (the edges of the cells and of the guides' ranges),
        // the guides' own starts and random u.
        std::vector<Real> us = {Real(0), std::nextafter(Real(1), Real(0))};
        for (const Real c : cdf) {
            us.push_back(c);
            us.push_back(std::nextafter(c, Real(0)));
            us.push_back(std::nextafter(c, Real(1)));
        }
        const std::size_t guides = (n + 3) / 4;
        for (std::size_t b = 0; b <= guides; ++b) us.push_back(Real(b) / Real(guides));
        for (int i = 0; i < 20000; ++i) us.push_back(random.uniform<Real>());
        int differ = 0;
        for (const Real u : us) {
            if (!(u >= 0 && u < 1)) continue;
            const std::size_t cell = distribution.sample(u).cell;
            if (cell != plain_cell(u)) ++differ;
            if (table[cell] == 0) ++differ;  // a zero cell is never drawn
        }
        CHECK(differ == 0);
    }
}

TEST_CASE_TEMPLATE("piecewise-constant 2D: density, frequencies and the inverse CDF", Real, float, double) {
    const std::size_t width = 4, height = 3;
    const std::vector<Real> table = {1, 2, 0, 1,  //
                                     0, 0, 0, 0,  //
                                     4, 1, 3, 0.5};
    double total = 0;
    for (const Real value : table) total += double(value);
    const prism::PiecewiseConstant2D<Real> distribution(table, width, height);
    CHECK(distribution.integral() == doctest::Approx(total / 12));

    double integral = 0;
    const int steps = 240;
    for (int y = 0; y < steps; ++y)
        for (int x = 0; x < steps; ++x)
            integral += double(distribution.pdf(Vec2<Real>((Real(x) + Real(0.5)) / steps, (Real(y) + Real(0.5)) / steps)));
    CHECK(integral / (steps * steps) == doctest::Approx(1).epsilon(1e-5));

    prism::Random random(5);
    const int count = 200000;
    std::vector<int> hits(table.size(), 0);
    for (int i = 0; i < count; ++i) {
        const Vec2<Real> u = random.uniform2<Real>();
        const auto sample = distribution.sample(u);
        const std::size_t column = std::size_t(sample.point.x * Real(width)), row = std::size_t(sample.point.y * Real(height));
        ++hits[row * width + column];
        CHECK(sample.pdf == doctest::Approx(double(distribution.pdf(sample.point))));
        const Vec2<Real> back = distribution.cdf(sample.point);
        CHECK(double(back.x) == doctest::Approx(double(u.x)).epsilon(1e-4));
        CHECK(double(back.y) == doctest::Approx(double(u.y)).epsilon(1e-4));
    }
    // 8 non-zero cells: 7 degrees of freedom, 24.3 is the 99.9% quantile.
    const double chi_square = pearson_chi_square(table, hits, count);
    CHECK(chi_square < 24.3);
}

// The white furnace, at the light: a constant environment L lights a point with the normal n.
// The course's diffuse term kd cos(theta) E, with E = sample.radiance = L(w) / p(w), estimates
// the integral of kd L cos(theta) over the hemisphere = pi kd L. With kd = rho / pi (a Lambertian
// BRDF of albedo rho), that is rho L: what is checked, within 1%, for every strategy and layout.
TEST_CASE_TEMPLATE("white furnace: every sampling strategy estimates rho L", Real, float, double) {
    const glm::vec3 environment(0.5f, 1.0f, 2.0f);
    const double rho = 0.8;
    const Vec3<Real> normals[] = {Vec3<Real>(0, 1, 0), Vec3<Real>(0, 0, -1), Vec3<Real>(0, 0, 1),
                                  glm::normalize(Vec3<Real>(0.3, -0.8, 0.5))};
    for (const Layout layout : {Layout::latlong, Layout::probe}) {
        // Constant everywhere, outside the probe's disc too: the furnace tests the light, not the
        // probe's rim.
        const auto map = map_of<Real>(filled(128, layout == Layout::latlong ? 64 : 128, environment), layout);
        for (const Sampling sampling : {Sampling::uniform, Sampling::cosine, Sampling::importance}) {
            const prism::EnvironmentLight<Real> light(map, sampling);
            for (const Vec3<Real>& normal : normals) {
                CAPTURE(int(layout));
                CAPTURE(int(sampling));
                CAPTURE(normal);
                const glm::dvec3 course = diffuse_estimate(light, normal, 200000).mean;  // kd = 1
                const glm::dvec3 lambertian = rho / pi * course;
                for (int c = 0; c < 3; ++c) {
                    CHECK(course[c] == doctest::Approx(pi * environment[c]).epsilon(0.01));
                    CHECK(lambertian[c] == doctest::Approx(rho * environment[c]).epsilon(0.01));
                }
            }
        }
    }
}

TEST_CASE_TEMPLATE("importance sampling: a sample's radiance is L / pdf of its own direction", Real, float, double) {
    prism::ProceduralSky sky;
    sky.sun_direction = {0.4, 0.5, -0.6};
    sky.sun_angle_degrees = 4;
    sky.sun_radiance = {5000, 4800, 4500};  // about 70% of the sky's power
    for (const Layout layout : {Layout::latlong, Layout::probe}) {
        CAPTURE(int(layout));
        const prism::EnvironmentLight<Real> light(map_of<Real>(prism::render_sky(sky, layout, 128, 2), layout),
                                                  Sampling::importance);
        prism::Random random(3);
        const prism::ShadingFrame<Real> at{Vec3<Real>(0), Vec3<Real>(0, 1, 0)};
        int towards_sun = 0, inconsistent = 0;
        const int count = 20000;
        for (int i = 0; i < count; ++i) {
            const auto sample = light.sample(at, random.uniform2<Real>());
            if (sample.radiance == Vec3<Real>(0)) continue;
            CHECK(std::isinf(sample.distance));
            const Real pdf = light.pdf(at, sample.direction);
            REQUIRE(pdf > 0);
            const Vec3<Real> expected = light.background(sample.direction) / pdf;
            // pdf() finds the cell again from the direction: a sample on a cell's border may, by
            // rounding, land in its neighbour.
            if (std::abs(double(sample.radiance.g / expected.g) - 1) > 1e-3) ++inconsistent;
            // The sun's disc, widened by the pixel (2.8 degrees) its light is spread over.
            if (glm::dot(glm::dvec3(sample.direction), glm::normalize(sky.sun_direction)) > std::cos(6 * pi / 180)) ++towards_sun;
        }
        CHECK(inconsistent < count / 1000);
        CHECK(towards_sun > count / 2);
    }
}

TEST_CASE_TEMPLATE("the same sky in lat-long and probe layouts gives the same background", Real, float, double) {
    prism::ProceduralSky sky;
    sky.sun_direction = {-0.5, 0.4, 0.3};
    sky.sun_angle_degrees = 8;
    sky.sun_radiance = {50, 45, 40};
    const int width = 512;
    const auto latlong = map_of<Real>(prism::render_sky(sky, Layout::latlong, width), Layout::latlong);
    const auto probe = map_of<Real>(prism::render_sky(sky, Layout::probe, width), Layout::probe);
    const glm::dvec3 sun = glm::normalize(sky.sun_direction);
    // Away from the sky's own edges (the horizon, the sun's rim) and from +Z, which the probe
    // squeezes into its rim, both layouts resample a smooth function: within 2%.
    const double margin = 2.0 * pi / 180;
    int compared = 0, off = 0;
    double worst = 0;
    for (const glm::dvec3& direction : sphere_directions(40000)) {
        if (std::abs(std::asin(direction.y)) < margin) continue;
        if (std::abs(std::acos(std::clamp(glm::dot(direction, sun), -1.0, 1.0)) - 4 * pi / 180) < margin) continue;
        if (direction.z > std::cos(margin)) continue;
        const glm::dvec3 a(latlong.radiance(Vec3<Real>(direction))), b(probe.radiance(Vec3<Real>(direction)));
        const glm::dvec3 truth = sky.radiance(direction);
        const double difference = glm::length(a - b) / glm::length(truth);
        worst = std::max(worst, difference);
        ++compared;
        if (difference > 0.02) ++off;
        CHECK(glm::length(a - truth) / glm::length(truth) < 0.02);
    }
    MESSAGE("lat-long vs probe: " << compared << " directions, worst relative difference " << worst);
    CHECK(compared > 30000);
    CHECK(off == 0);
}

TEST_CASE("every environment map in the shared data reads, tiled and half-float EXRs included") {
    if (!fs::exists(shared_envmaps())) {
        MESSAGE("skipped: " << shared_envmaps() << " not found");
        return;
    }
    struct Expected {
        const char* name;
        int width, height;
    };
    const Expected files[] = {{"probulator_grace_latlong.hdr", 256, 128},       {"probulator_pisa_latlong.hdr", 256, 128},
                              {"pbrtv2_grace_latlong.exr", 1024, 512},          {"KernerEnvLatLong.exr", 1024, 512},
                              {"polyhaven_venice_sunset_1k_latlong.hdr", 1024, 512}, {"spica_uffizi_latlong.hdr", 1200, 600},
                              {"uffizi_probe_512_derived.hdr", 512, 512}};
    for (const Expected& file : files) {
        CAPTURE(file.name);
        const prism::Image image = prism::read_image(shared_envmaps() / file.name);
        CHECK(image.width == file.width);
        CHECK(image.height == file.height);
        double sum = 0;
        bool finite = true;
        for (const glm::vec3& pixel : image.pixels) {
            finite = finite && std::isfinite(pixel.r) && std::isfinite(pixel.g) && std::isfinite(pixel.b);
            sum += pixel.r + pixel.g + pixel.b;
        }
        CHECK(finite);
        CHECK(sum > 0);
    }
    // The tiled file's 64x64 tiles land where they belong: luminance changes no more across a
    // tile border than between neighbouring pixels inside a tile (misplaced tiles would make
    // every border a cliff).
    const prism::Image kerner = prism::read_image(shared_envmaps() / "KernerEnvLatLong.exr");
    auto log_luminance = [&](int x, int y) { return std::log(1e-4 + prism::luminance(kerner(x, y))); };
    double across = 0, inside = 0;
    int across_count = 0, inside_count = 0;
    for (int y = 1; y < kerner.height; ++y)
        for (int x = 1; x < kerner.width; ++x) {
            const double step = std::abs(log_luminance(x, y) - log_luminance(x - 1, y)) +
                                std::abs(log_luminance(x, y) - log_luminance(x, y - 1));
            if (x % 64 == 0 || y % 64 == 0) {
                across += step;
                ++across_count;
            } else {
                inside += step;
                ++inside_count;
            }
        }
    CHECK(across / across_count < 1.3 * inside / inside_count);
}

TEST_CASE_TEMPLATE("Uffizi: the lat-long map and the probe derived from it light the sphere alike", Real, float, double) {
    if (!fs::exists(shared_envmaps())) {
        MESSAGE("skipped: " << shared_envmaps() << " not found");
        return;
    }
    const auto latlong = map_of<Real>(prism::read_image(shared_envmaps() / "spica_uffizi_latlong.hdr"), Layout::latlong);
    const auto probe = map_of<Real>(prism::read_image(shared_envmaps() / "uffizi_probe_512_derived.hdr"), Layout::probe);
    // The lat-long map mirrored left to right: what a map stored in the other orientation would
    // look like through the course's mapping.
    auto mirrored = [&](const glm::dvec3& d) { return glm::dvec3(latlong.radiance(Vec3<Real>(Real(-d.x), Real(d.y), Real(d.z)))); };
    glm::dvec3 mean_latlong(0.0), mean_probe(0.0);
    std::vector<double> differences, mirrored_differences;
    const auto directions = sphere_directions(100000);
    for (const glm::dvec3& direction : directions) {
        const glm::dvec3 a(latlong.radiance(Vec3<Real>(direction))), b(probe.radiance(Vec3<Real>(direction)));
        mean_latlong += a;
        mean_probe += b;
        const double ya = prism::luminance(a), yb = prism::luminance(b), ym = prism::luminance(mirrored(direction));
        differences.push_back(std::abs(ya - yb) / std::max(ya + yb, 1e-3));
        mirrored_differences.push_back(std::abs(ym - yb) / std::max(ym + yb, 1e-3));
    }
    mean_latlong /= double(directions.size());
    mean_probe /= double(directions.size());
    for (int c = 0; c < 3; ++c) CHECK(mean_probe[c] == doctest::Approx(mean_latlong[c]).epsilon(0.03));
    auto median = [](std::vector<double> values) {
        std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(values.size() / 2), values.end());
        return values[values.size() / 2];
    };
    const double agreement = median(differences), mirrored_agreement = median(mirrored_differences);
    MESSAGE("Uffizi mean radiance: lat-long " << mean_latlong.g << ", probe " << mean_probe.g
                                              << "; median |dY|/(Y1+Y2): " << agreement << " (mirrored: " << mirrored_agreement << ")");
    // Direction by direction too: the course's lat-long mapping on the file as stored is the
    // orientation the probe was made with, and the mirror image is not.
    CHECK(agreement < 0.02);
    CHECK(mirrored_agreement > 5 * agreement);
}

TEST_CASE_TEMPLATE("Venice sunset: importance sampling beats cosine sampling facing the sun", Real, float, double) {
    if (!fs::exists(shared_envmaps())) {
        MESSAGE("skipped: " << shared_envmaps() << " not found");
        return;
    }
    const auto map = map_of<Real>(prism::read_image(shared_envmaps() / "polyhaven_venice_sunset_1k_latlong.hdr"), Layout::latlong);
    const prism::Image& image = map.image();
    std::size_t brightest = 0;
    for (std::size_t i = 0; i < image.pixels.size(); ++i)
        if (prism::luminance(image.pixels[i]) > prism::luminance(image.pixels[brightest])) brightest = i;
    const Vec2<Real> sun_uv((Real(brightest % std::size_t(image.width)) + Real(0.5)) / Real(image.width),
                            (Real(brightest / std::size_t(image.width)) + Real(0.5)) / Real(image.height));
    const Vec3<Real> sun = glm::normalize(map.direction(sun_uv));

    // Cosine sampling meets the sun (a few pixels of luminance ~2000) about once in 50,000
    // samples, so its variance needs many samples to be measured at all.
    const int count = 1000000;
    const Estimate cosine = diffuse_estimate(prism::EnvironmentLight<Real>(map, Sampling::cosine), sun, count);
    const Estimate importance = diffuse_estimate(prism::EnvironmentLight<Real>(map, Sampling::importance), sun, count);
    const double ratio = importance.luminance_variance / cosine.luminance_variance;
    MESSAGE("Venice, facing the sun: mean Y cosine " << prism::luminance(cosine.mean) << ", importance "
                                                     << prism::luminance(importance.mean) << "; variance ratio " << ratio);
    // Both estimate the same integral...
    CHECK(prism::luminance(importance.mean) == doctest::Approx(prism::luminance(cosine.mean)).epsilon(0.05));
    // ...importance sampling with far less noise.
    CHECK(ratio < 0.1);  // measured: 0.02 (float and double, several seeds)
}

TEST_CASE("EnvironmentLight and EnvironmentBackground from a scene") {
    scene::Scene description;
    const auto sky = std::make_shared<const prism::Image>(filled(8, 4, glm::vec3(2.0f)));
    description.images.push_back({"sky.exr", std::make_shared<const prism::Texels>(sky), true});
    description.environment_lights.push_back({"1", 0, Layout::latlong, Sampling::importance, {1.0, 0.5, 0.25}});
    CHECK(prism::scene::light_kinds(description) == prism::scene::bit(prism::EnvironmentLight<float>::kind));
    const auto lights = prism::EnvironmentLight<double>::from_scene(description);
    REQUIRE(lights.size() == 1);
    CHECK(lights[0].background({0, 0, -1}) == Vec3<double>(2.0, 1.0, 0.5));  // the scale applies
    // The light reads the scene's decoded image itself, not a copy.
    CHECK(prism::EnvironmentLight<float>::map_of(description, description.environment_lights[0]).shared_image() == sky);
    CHECK(prism::EnvironmentLight<double>::map_of(description, description.environment_lights[0]).shared_image() == sky);

    const prism::EnvironmentBackground<float> background(description), shared(prism::EnvironmentLight<float>::from_scene(description));
    CHECK(background.present());
    CHECK(background.radiance({0, 1, 0}) == Vec3<float>(2.0f, 1.0f, 0.5f));
    CHECK(shared.radiance({1, 0, 0}) == Vec3<float>(2.0f, 1.0f, 0.5f));
    CHECK_FALSE(prism::EnvironmentBackground<float>().present());

    // In a light set beside other types, as a renderer's Config would hold it.
    const prism::LightSet<double, prism::PointLight, prism::EnvironmentLight> set(description);
    CHECK(set.size() == 1);
    CHECK(prism::Lights<prism::PointLight, prism::EnvironmentLight>::kinds ==
          (prism::scene::bit(prism::scene::LightKind::point) | prism::scene::bit(prism::scene::LightKind::environment)));
    int visited = 0;
    set.for_each([&](const auto& light) {
        const auto sample = light.sample({Vec3<double>(0), Vec3<double>(0, 1, 0)}, Vec2<double>(0.25, 0.5));
        CHECK(sample.radiance.g > 0);
        CHECK(std::isinf(sample.distance));
        ++visited;
    });
    CHECK(visited == 1);
    const auto* environment = set.of_type<prism::EnvironmentLight>();
    REQUIRE(environment != nullptr);
    const prism::ShadingFrame<double> up{Vec3<double>(0), Vec3<double>(0, 1, 0)};
    const auto sample = environment->front().sample(up, Vec2<double>(0.25, 0.5));
    CHECK(sample.radiance.g == doctest::Approx(1.0 / environment->front().pdf(up, sample.direction)));  // L = 2 * 0.5

    description.environment_lights[0].image = 3;
    CHECK_THROWS_AS(prism::EnvironmentLight<float>::from_scene(description), prism::io::LoadError);
}

// Runs only where ctest gives it the command (envmap/command in tests/CMakeLists.txt).
TEST_CASE("prism-envmap writes a map that reads back, and refuses bad arguments") {
    const char* command = std::getenv("PRISM_ENVMAP");
    if (!command) {
        MESSAGE("skipped: PRISM_ENVMAP (the prism-envmap binary) is not set; ctest's envmap/command sets it");
        return;
    }
    const prism_test::TemporaryFolder folder("prism_envmap_");
    auto run = [&](const std::string& arguments) {
        const int status = std::system(("\"" + std::string(command) + "\" " + arguments + " > /dev/null 2>&1").c_str());
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    };
    const fs::path sky = folder.path() / "sky.exr", probe = folder.path() / "probe.exr", constant = folder.path() / "constant.exr";
    REQUIRE(run("--layout latlong --width 64 --samples 2 --sun-direction 0,1,0 --sun-angle 20 --sun-radiance 100,100,100 "
                "--output \"" + sky.string() + "\"") == 0);
    const prism::Image latlong = prism::read_image(sky);
    CHECK(latlong.width == 64);
    CHECK(latlong.height == 32);
    CHECK(latlong(10, 0).g == doctest::Approx(100));     // the top row is the sun, straight up
    CHECK(latlong(10, 31).g == doctest::Approx(0.27));   // the bottom row the ground (default colour)

    REQUIRE(run("--layout probe --width 64 --constant 1.5,1.5,1.5 --output \"" + constant.string() + "\"") == 0);
    const prism::Image disc = prism::read_image(constant);
    CHECK(disc.width == 64);
    CHECK(disc.height == 64);
    CHECK(disc(32, 32).r == doctest::Approx(1.5));
    CHECK(disc(0, 0).r == 0);  // outside the disc

    // Each bad argument: exit status 2, and no file.
    for (const std::string bad : {"--width 1", "--width ten", "--layout cube", "--sun-direction 0,0,0", "--sun-angle 0",
                                  "--sun-radiance 1,2", "--constant -1,1,1", "--constant 1,1,1 --zenith 1,1,1", "--bogus",
                                  "--width 64 --width 32"}) {
        CAPTURE(bad);
        CHECK(run(bad + " --output \"" + probe.string() + "\"") == 2);
        CHECK_FALSE(fs::exists(probe));
    }
    CHECK(run("--width 64") == 2);                                             // no --output
    CHECK(run("--output \"" + (folder.path() / "sky.png").string() + "\"") == 2);  // not an EXR
    CHECK_FALSE(fs::exists(folder.path() / "sky.png"));
}
