// The samplers of sampling/sampler.hpp, for float and double: each keeps the promise of its
// construction (ZSobol: Sobol' points against published values, every pixel's samples a
// (0, m, 2)-net in every pair of dimensions; Stratified: one sample per stratum of every
// dimension and per cell of every pair), draws the same numbers for the same (pixel, sample,
// dimension) whatever was drawn before, and uses no dimension twice (no correlation between the
// dimensions two bounces take).
#include <prism/render/renderer.hpp>
#include <prism/sampling/sampler.hpp>
#include <prism/sampling/sampler_choice.hpp>
#include <prism/sampling/sobol.hpp>
#include <prism/sampling/stratified.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <set>
#include <stdexcept>
#include <utility>
#include <vector>

namespace {

namespace samplers_test {

using prism::Vec2;

// Sample `sample` of a pixel's sampler: `skipped` dimensions passed, then one pair.
template <class Real, class Sampler>
Vec2<Real> pair_at(Sampler sampler, int sample, int skipped) {
    sampler.start_sample(sample);
    sampler.template skip<Real>(skipped);
    return sampler.template uniform2<Real>();
}
template <class Real, class Sampler>
Real single_at(Sampler sampler, int sample, int skipped) {
    sampler.start_sample(sample);
    sampler.template skip<Real>(skipped);
    return sampler.template uniform<Real>();
}

// Whether n = 2^m points form a (0, m, 2)-net: every partition of the unit square into 2^m
// equal boxes 2^a wide and 2^(m-a) high holds one point in each box.
template <class Real>
bool is_net(const std::vector<Vec2<Real>>& points) {
    const int n = int(points.size());
    int m = 0;
    while ((1 << m) < n) ++m;
    for (int a = 0; a <= m; ++a) {
        const int columns = 1 << a, rows = 1 << (m - a);
        std::set<std::pair<int, int>> boxes;
        for (const auto& p : points) boxes.insert({int(p.x * columns), int(p.y * rows)});
        if (int(boxes.size()) != n) return false;
    }
    return true;
}

// Whether the values fall one in each of the n strata [k/n, (k+1)/n).
template <class Real>
bool one_per_stratum(const std::vector<Real>& values) {
    std::set<int> strata;
    for (Real v : values) strata.insert(int(std::floor(double(v) * double(values.size()))));
    return strata.size() == values.size() && *strata.begin() >= 0 && *strata.rbegin() < int(values.size());
}

// Pearson's correlation of two equally long lists.
double correlation(const std::vector<double>& a, const std::vector<double>& b) {
    const double n = double(a.size());
    double ma = 0, mb = 0;
    for (std::size_t i = 0; i < a.size(); ++i) ma += a[i] / n, mb += b[i] / n;
    double ab = 0, aa = 0, bb = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        ab += (a[i] - ma) * (b[i] - mb);
        aa += (a[i] - ma) * (a[i] - ma);
        bb += (b[i] - mb) * (b[i] - mb);
    }
    return ab / std::sqrt(aa * bb);
}

// Over 32 x 32 pixels and `samples` samples each, drawn as a render draws them (one sampler a
// pixel, its samples in order), the correlation between the number of dimension `d1` and of
// `d2` > d1 (as two bounces draw them), and whether every number is in [0, 1).
template <class Real, class Pattern>
std::pair<double, bool> dimension_correlation(const Pattern& pattern, int samples, int d1, int d2) {
    std::vector<double> a, b;
    bool in_range = true;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            auto sampler = pattern.for_pixel(x, y);
            for (int s = 0; s < samples; ++s) {
                sampler.start_sample(s);
                sampler.template skip<Real>(d1);
                const Real u = sampler.template uniform<Real>();
                sampler.template skip<Real>(d2 - d1 - 1);
                const Real v = sampler.template uniform<Real>();
                in_range = in_range && u >= 0 && u < 1 && v >= 0 && v < 1;
                a.push_back(double(u));
                b.push_back(double(v));
            }
        }
    return {correlation(a, b), in_range};
}

// ZSobol's numbers by their definition, one sample at a time (sampling/sobol.hpp): the index
// (morton(x, y) << log2 spp) | sample, as a 32-bit integer, with each bit from the top flipped by
// a hash of the bits above it and the dimension's salt (a nested uniform scramble: Owen's
// scramble of the index read as a fraction); then Sobol' dimension 0 (and 1,
// for a pair) Owen-scrambled with the dimension's keys. Nothing cached, nothing shared by a
// block.
struct ZSobolReference {
    int log2_samples;
    prism::sampling::ZSobolKeys keys;

    ZSobolReference(int samples, int, int, std::uint64_t seed) : keys(prism::sampling::ZSobolKeys::of(seed)) {
        log2_samples = 0;
        while ((1 << log2_samples) < samples) ++log2_samples;
    }
    std::uint32_t index(int x, int y, int sample, int dimension) const {
        const std::uint64_t salt = prism::sampling::dimension_key(keys.salt, dimension);
        const std::uint64_t original =
            (prism::sampling::morton_2d(std::uint32_t(x), std::uint32_t(y)) << log2_samples) | std::uint32_t(sample);
        const std::uint64_t above = original >> 32;
        const std::uint32_t key = std::uint32_t(above == 0 ? salt : prism::mix_bits(salt ^ above));
        return prism::sampling::owen_scramble(std::uint32_t(original), key);
    }
    template <class Real>
    Real single(int x, int y, int sample, int dimension) const {
        const auto key = std::uint32_t(prism::sampling::dimension_key(keys.single, dimension));
        return prism::sampling::unit_from_bits<Real>(
            prism::sampling::owen_scramble_reversed(index(x, y, sample, dimension), key));
    }
    template <class Real>
    Vec2<Real> pair(int x, int y, int sample, int dimension) const {
        const std::uint64_t key = prism::sampling::dimension_key(keys.pair, dimension);
        const std::uint32_t i = index(x, y, sample, dimension);
        const std::uint32_t second = prism::sampling::reverse_bits(prism::sampling::sobol_dimension1_bitwise(i));
        return {prism::sampling::unit_from_bits<Real>(prism::sampling::owen_scramble_reversed(i, std::uint32_t(key))),
                prism::sampling::unit_from_bits<Real>(
                    prism::sampling::owen_scramble_reversed(second, std::uint32_t(key >> 32)))};
    }
};

}  // namespace samplers_test

using namespace samplers_test;

}  // namespace

static_assert(prism::PixelSampler<prism::IndependentSampler, float>);
static_assert(prism::PixelSampler<prism::ZSobolSampler, double>);
static_assert(prism::PixelSampler<prism::StratifiedSampler, float>);
static_assert(prism::SamplerPattern<prism::IndependentPattern, float>);
static_assert(prism::SamplerPattern<prism::ZSobolPattern, float>);
static_assert(prism::SamplerPattern<prism::StratifiedPattern, double>);
// A pixel's ZSobol sampler reads its pattern's tables, so a pattern about to end makes none
// (for_pixel const&& deleted); a stream's pattern holds nothing its samplers read.
template <class P>
concept makes_sampler_as_temporary = requires(int x) { std::declval<const P&&>().for_pixel(x, x); };
static_assert(!makes_sampler_as_temporary<prism::ZSobolPattern>);
static_assert(!makes_sampler_as_temporary<prism::ChosenPattern>);
static_assert(makes_sampler_as_temporary<prism::IndependentPattern>);

TEST_CASE("Samplers: Sobol' dimensions 0 and 1 give the published first points") {
    // The unscrambled two-dimensional Sobol' points 0-15 in Gray-code order (Bratley and Fox's
    // ordering, as scipy.stats.qmc.Sobol(d=2, scramble=False) lists them): point i of that
    // order is point i ^ (i >> 1) of the natural one.
    const double published[16][2] = {
        {0, 0},           {0.5, 0.5},       {0.75, 0.25},     {0.25, 0.75},     {0.375, 0.375},   {0.875, 0.875},
        {0.625, 0.125},   {0.125, 0.625},   {0.1875, 0.3125}, {0.6875, 0.8125}, {0.9375, 0.0625}, {0.4375, 0.5625},
        {0.3125, 0.1875}, {0.8125, 0.6875}, {0.5625, 0.4375}, {0.0625, 0.9375}};
    for (std::uint32_t i = 0; i < 16; ++i) {
        const std::uint32_t natural = i ^ (i >> 1);
        CAPTURE(i);
        CHECK(prism::sampling::sobol_dimension0(natural) * 0x1p-32 == published[i][0]);
        CHECK(prism::sampling::sobol_dimension1(natural) * 0x1p-32 == published[i][1]);
    }
    // Owen scrambling permutes elementary intervals: the first 2^m points stay a net.
    std::vector<Vec2<double>> scrambled;
    for (std::uint32_t i = 0; i < 256; ++i)
        scrambled.push_back({prism::sampling::owen_scramble(prism::sampling::sobol_dimension0(i), 0x1234567u) * 0x1p-32,
                             prism::sampling::owen_scramble(prism::sampling::sobol_dimension1(i), 0x89abcdefu) * 0x1p-32});
    CHECK(is_net(scrambled));
    CHECK(scrambled[1].x != 0.5);  // scrambled at all
}

TEST_CASE_TEMPLATE("Samplers: ZSobol makes each pixel's samples a (0, m, 2)-net in every pair of dimensions", Real, float,
                   double) {
    for (const int samples : {4, 8, 16, 32, 64}) {
        const prism::ZSobolPattern pattern(samples, 640, 480, 7);
        for (const std::pair<int, int>& pixel : {std::pair{0, 0}, std::pair{1, 0}, std::pair{313, 207}, std::pair{639, 479}}) {
            const int x = pixel.first, y = pixel.second;  // named, not bound: doctest's CAPTURE takes them
            for (int dimension = 0; dimension < 12; dimension += 2) {
                std::vector<Vec2<Real>> points;
                std::vector<Real> singles;
                for (int s = 0; s < samples; ++s) {
                    points.push_back(pair_at<Real>(pattern.for_pixel(x, y), s, dimension));
                    singles.push_back(single_at<Real>(pattern.for_pixel(x, y), s, dimension));
                }
                CAPTURE(samples);
                CAPTURE(x);
                CAPTURE(y);
                CAPTURE(dimension);
                CHECK(is_net(points));
                CHECK(one_per_stratum(singles));
            }
        }
    }
}

TEST_CASE_TEMPLATE("Samplers: ZSobol's blocks of samples draw each sample's numbers by their one-sample definition, bit for bit",
                   Real, float, double) {
    // Sample counts below, at and past a block, odd and even powers of two and neither; pixels
    // at the corners; dimensions past the kept ones (cached_dimensions), each drawn as a single
    // by some samples and in a pair by others; samples drawn in an order that leaves and
    // revisits blocks, and a sampler copied midway. Two image sizes, a pixel past the image,
    // and one whose index reaches past 32 bits (its bits above them go into the shuffle's key).
    for (const int samples : {1, 2, 3, 5, 8, 16, 32, 37, 64, 128, 256})
    for (const std::pair<int, int>& size : {std::pair{300, 200}, std::pair{12, 7}}) {
        const prism::ZSobolPattern pattern(samples, size.first, size.second, 11);
        const ZSobolReference reference(samples, size.first, size.second, 11);
        for (const std::pair<int, int>& pixel : {std::pair{0, 0}, std::pair{size.first - 1, size.second - 1},
                                                 std::pair{size.first * 2 / 5, size.second / 4},
                                                 std::pair{size.first + 5, size.second + 3}, std::pair{70000, 70001}}) {
            const int x = pixel.first, y = pixel.second;
            prism::ZSobolSampler sampler = pattern.for_pixel(x, y);
            std::vector<int> order;
            for (int s = samples - 1; s >= 0; s -= 2) order.push_back(s);
            for (int s = samples - 2; s >= 0; s -= 2) order.push_back(s);
            int mismatches = 0;
            const auto draw = [&](prism::ZSobolSampler& drawing, int s) {
                drawing.start_sample(s);
                for (int dimension = 0; dimension < 72;) {
                    if ((dimension + s) % 3 == 0) {
                        mismatches += drawing.template uniform<Real>() != reference.template single<Real>(x, y, s, dimension);
                        dimension += 1;
                    } else {
                        mismatches += drawing.template uniform2<Real>() != reference.template pair<Real>(x, y, s, dimension);
                        dimension += 2;
                    }
                }
            };
            for (std::size_t k = 0; k < order.size(); ++k) {
                if (k % 4 == 1) {
                    // A copy made within a block (the sampler's last sample was in its block).
                    prism::ZSobolSampler copy = sampler;
                    draw(copy, order[k]);
                    continue;
                }
                if (k == order.size() / 2) sampler = prism::ZSobolSampler(sampler);
                draw(sampler, order[k]);
            }
            CAPTURE(samples);
            CAPTURE(x);
            CAPTURE(y);
            CHECK(mismatches == 0);
        }
    }
}

TEST_CASE_TEMPLATE("Samplers: Stratified puts one sample in each stratum of every dimension and each cell of every pair",
                   Real, float, double) {
    for (const int samples : {1, 5, 9, 12, 16, 30}) {
        const prism::StratifiedPattern pattern(samples, 11);
        int columns = 1;
        while (columns * columns < samples) ++columns;
        const int rows = (samples + columns - 1) / columns;
        for (const std::pair<int, int>& pixel : {std::pair{0, 0}, std::pair{5, 3}}) {
            const int x = pixel.first, y = pixel.second;
            for (int dimension = 0; dimension < 10; dimension += 2) {
                std::vector<Real> singles, xs, ys;
                std::set<std::pair<int, int>> cells;
                std::set<int> x_strata, y_strata;
                for (int s = 0; s < samples; ++s) {
                    singles.push_back(single_at<Real>(pattern.for_pixel(x, y), s, dimension));
                    const Vec2<Real> p = pair_at<Real>(pattern.for_pixel(x, y), s, dimension);
                    CHECK((p.x >= 0 && p.x < 1 && p.y >= 0 && p.y < 1));
                    cells.insert({int(p.x * columns), int(p.y * rows)});
                    x_strata.insert(int(double(p.x) * columns * rows));
                    y_strata.insert(int(double(p.y) * columns * rows));
                }
                CAPTURE(samples);
                CAPTURE(dimension);
                CHECK(one_per_stratum(singles));
                CHECK(int(cells.size()) == samples);
                CHECK(int(x_strata.size()) == samples);  // each axis alone: m k strata, one per sample
                CHECK(int(y_strata.size()) == samples);
            }
        }
    }
}

TEST_CASE_TEMPLATE("Samplers: a sample's numbers depend on its pixel, index and dimension, not on what was drawn before",
                   Real, float, double) {
    const prism::ZSobolPattern sobol(16, 64, 64, 3);
    const prism::StratifiedPattern stratified(16, 3);
    const auto check = [](const auto& pattern) {
        auto a = pattern.for_pixel(9, 4);
        auto b = pattern.for_pixel(9, 4);
        // a draws sample 3 after samples 0-2 and other draws; b draws sample 3 fresh.
        for (int s = 0; s < 3; ++s) {
            a.start_sample(s);
            for (int k = 0; k < 5; ++k) (void)a.template uniform2<Real>();
        }
        a.start_sample(3);
        b.start_sample(3);
        for (int k = 0; k < 8; ++k) {
            CHECK(a.template uniform<Real>() == b.template uniform<Real>());
            const Vec2<Real> pa = a.template uniform2<Real>(), pb = b.template uniform2<Real>();
            CHECK(pa == pb);
        }
        // skip(n) passes exactly n dimensions.
        auto c = pattern.for_pixel(9, 4), d = pattern.for_pixel(9, 4);
        c.start_sample(5);
        d.start_sample(5);
        c.template skip<Real>(3);
        (void)d.template uniform<Real>();
        (void)d.template uniform2<Real>();
        CHECK(c.template uniform<Real>() == d.template uniform<Real>());
        // Neighbouring pixels draw other numbers.
        CHECK(single_at<Real>(pattern.for_pixel(9, 4), 0, 0) != single_at<Real>(pattern.for_pixel(10, 4), 0, 0));
    };
    check(sobol);
    check(stratified);
}

TEST_CASE_TEMPLATE("Samplers: Independent is the pixel's stream, drawn in order across its samples", Real, float, double) {
    const prism::IndependentPattern pattern(4, 21);
    auto sampler = pattern.for_pixel(7, 2);
    prism::Random stream = prism::Random::for_pixel(7, 2, 21);
    for (int s = 0; s < 4; ++s) {
        sampler.start_sample(s);
        CHECK(sampler.template uniform<Real>() == stream.uniform<Real>());
        CHECK(sampler.template uniform2<Real>() == stream.uniform2<Real>());
        sampler.template skip<Real>(3);
        stream.skip<Real>(3);
    }
}

TEST_CASE_TEMPLATE("Samplers: no dimension is reused: two bounces' dimensions are uncorrelated", Real, float, double) {
    // 32 x 32 pixels x 16 samples: 16,384 pairs, so a correlation's standard error is about
    // 0.008 for independent numbers; 0.05 is six of them. Dimensions 4 and 6, 5 and 9, and 0 and
    // 12 stand for one bounce's numbers against the next's.
    const prism::ZSobolPattern sobol(16, 32, 32, 5);
    const prism::StratifiedPattern stratified(16, 5);
    const prism::IndependentPattern independent(16, 5);
    for (const std::pair<int, int>& dimensions : {std::pair{4, 6}, std::pair{5, 9}, std::pair{0, 12}}) {
        const int d1 = dimensions.first, d2 = dimensions.second;
        CAPTURE(d1);
        CAPTURE(d2);
        for (const auto& [r, in_range] : {dimension_correlation<Real>(sobol, 16, d1, d2),
                                          dimension_correlation<Real>(stratified, 16, d1, d2),
                                          dimension_correlation<Real>(independent, 16, d1, d2)}) {
            CHECK(std::abs(r) < 0.05);
            CHECK(in_range);
        }
    }
}

TEST_CASE_TEMPLATE("Samplers: at 16 samples a pixel, stratified and ZSobol estimate a disk's area and a smooth integral with less error than independent samples",
                   Real, float, double) {
    // Each of 32 x 32 pixels estimates, from the pair at dimension 6 of its 16 samples (the
    // numbers of a later bounce, not the pixel's position), the area of a disk of radius 0.3
    // (an edge, as a soft shadow's) and the integral of exp(-(a u + b v)) over the unit square.
    // As in a render, the integrand differs from pixel to pixel (the disk's centre, a and b):
    // ZSobol's pixels share one scrambled sequence, and their errors are spread (blue noise)
    // only where their integrands differ. The error is the root mean square over the pixels.
    // Independent samples' is the Monte Carlo rate (0.12 for the disk); stratified points on
    // an edge converge as n^-3/4, on a smooth integrand as n^-1 or faster.
    const double pi = 3.14159265358979323846;
    const auto rms_errors = [&](const auto& pattern) {
        double disk_error = 0, smooth_error = 0;
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; ++x) {
                const double cx = 0.35 + 0.3 * ((x * 7 + y * 3) % 32) / 31.0, cy = 0.35 + 0.3 * ((x * 5 + y * 11) % 32) / 31.0;
                const double a = 0.5 + 1.5 * x / 31.0, b = 0.5 + 1.5 * y / 31.0;
                const double area = pi * 0.09, integral = (1 - std::exp(-a)) * (1 - std::exp(-b)) / (a * b);
                auto sampler = pattern.for_pixel(x, y);
                double inside = 0, estimate = 0;
                for (int s = 0; s < 16; ++s) {
                    sampler.start_sample(s);
                    sampler.template skip<Real>(6);
                    const Vec2<Real> p = sampler.template uniform2<Real>();
                    const double u = double(p.x), v = double(p.y);
                    inside += (u - cx) * (u - cx) + (v - cy) * (v - cy) < 0.09 ? 1.0 / 16 : 0.0;
                    estimate += std::exp(-(a * u + b * v)) / 16;
                }
                disk_error += (inside - area) * (inside - area) / 1024;
                smooth_error += (estimate - integral) * (estimate - integral) / 1024;
            }
        return std::pair{std::sqrt(disk_error), std::sqrt(smooth_error)};
    };
    const auto independent = rms_errors(prism::IndependentPattern(16, 1));
    const auto stratified = rms_errors(prism::StratifiedPattern(16, 1));
    const auto sobol = rms_errors(prism::ZSobolPattern(16, 32, 32, 1));
    MESSAGE("disk RMSE: independent ", independent.first, ", stratified ", stratified.first, ", ZSobol ", sobol.first);
    MESSAGE("smooth RMSE: independent ", independent.second, ", stratified ", stratified.second, ", ZSobol ",
            sobol.second);
    CHECK(independent.first > 0.08);  // the Monte Carlo rate, sqrt(p (1 - p) / 16) = 0.12
    CHECK(stratified.first < 0.7 * independent.first);
    CHECK(sobol.first < 0.7 * independent.first);
    CHECK(stratified.second < 0.3 * independent.second);
    CHECK(sobol.second < 0.3 * independent.second);
}

TEST_CASE_TEMPLATE("Samplers: ZSobol spreads a pixel's error as blue noise: neighbouring pixels' errors cancel, independent samples' do not",
                   Real, float, double) {
    // Every one of 64 x 64 pixels estimates the same integrals (a disk's area, an edge as a
    // soft shadow's, and the smooth exp(-(1.3 u + 0.7 v)) over the unit square) from a pair of
    // its 16 samples. White noise keeps the error of a k x k window's mean at 1 / k of a
    // pixel's; ZSobol's pixels in Morton order take complementary parts of one sequence (Ahmed
    // and Wonka 2020), so a window's mean is far better than that. `spread` is the RMS of the
    // windows' means times k over the RMS of the pixels' errors: 1 for white noise. Here
    // (dimensions 0 and 6): ZSobol 0.62-0.70 (the disk) and 0.06 (smooth) over aligned 4 x 4
    // windows, 0.65-0.71 and 0.46-0.64 over 8 x 8 windows shifted by a pixel; independent
    // samples 0.82-1.14; ZSobol with its pixels out of Morton order 0.81-1.03.
    constexpr int n = 64, samples = 16;
    const double pi = 3.14159265358979323846;
    const double area = pi * 0.09, a = 1.3, b = 0.7;
    const double integral = (1 - std::exp(-a)) * (1 - std::exp(-b)) / (a * b);
    const auto spreads = [&](const auto& pattern, int dimension) {
        std::vector<double> disk(n * n), smooth(n * n);
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                auto sampler = pattern.for_pixel(x, y);
                double inside = 0, estimate = 0;
                for (int s = 0; s < samples; ++s) {
                    sampler.start_sample(s);
                    sampler.template skip<Real>(dimension);
                    const Vec2<Real> p = sampler.template uniform2<Real>();
                    const double u = double(p.x), v = double(p.y);
                    inside += (u - 0.5) * (u - 0.5) + (v - 0.5) * (v - 0.5) < 0.09 ? 1.0 / samples : 0.0;
                    estimate += std::exp(-(a * u + b * v)) / samples;
                }
                disk[std::size_t(y * n + x)] = inside - area;
                smooth[std::size_t(y * n + x)] = estimate - integral;
            }
        // The spread over k x k windows whose corners are `offset` pixels from the image's
        // (the windows wrap around its edges).
        const auto spread = [&](const std::vector<double>& error, int k, int offset) {
            double pixels = 0, windows = 0;
            for (const double e : error) pixels += e * e;
            for (int wy = offset; wy < n + offset; wy += k)
                for (int wx = offset; wx < n + offset; wx += k) {
                    double mean = 0;
                    for (int y = wy; y < wy + k; ++y)
                        for (int x = wx; x < wx + k; ++x) mean += error[std::size_t((y % n) * n + x % n)] / (k * k);
                    windows += mean * mean;
                }
            return std::sqrt(windows / double((n / k) * (n / k))) * k / std::sqrt(pixels / double(n * n));
        };
        return std::array<double, 4>{spread(disk, 4, 0), spread(smooth, 4, 0), spread(disk, 8, 1), spread(smooth, 8, 1)};
    };
    for (const int dimension : {0, 6}) {
        const auto sobol = spreads(prism::ZSobolPattern(samples, n, n, 3), dimension);
        const auto independent = spreads(prism::IndependentPattern(samples, 3), dimension);
        CAPTURE(dimension);
        MESSAGE("spread (disk and smooth, aligned 4 x 4, shifted 8 x 8): ZSobol ", sobol[0], " ", sobol[1], " ", sobol[2], " ",
                sobol[3], "; independent ", independent[0], " ", independent[1], " ", independent[2], " ", independent[3]);
        for (const double white : independent) CHECK(white > 0.7);
        CHECK(sobol[0] < 0.8);
        CHECK(sobol[1] < 0.25);
        CHECK(sobol[2] < 0.9);
        CHECK(sobol[3] < 0.75);
    }
}

TEST_CASE_TEMPLATE("Samplers: on straight edges ZSobol's pixel pair leaves less error than the jittered grid of the independent sampler's camera samples",
                   Real, float, double) {
    // Where a render's error is anti-aliasing (geometric edges and the edges of visible
    // emitters), the independent sampler is not independent: its camera samples are a jittered
    // grid (camera_samples). This measures what ZSobol's pixel pair (dimensions 0 and 1, a
    // (0, m, 2)-net) gains over that grid on straight edges: each of 64 x 64 pixels covers a
    // half-plane v < m u + b (u and v swapped in half of them) of a slope in [-1, 1] and an
    // offset that crosses the pixel, whose exact area is the integral of clamp(m u + b, 0, 1).
    // It is 0.83-0.88 of the grid's error here, and bench/RESULTS.md ("The samplers") shows
    // that this bounds sobol's error over independent's on hw3 metal_plates_area: 0.72 at 16
    // and 64 samples, 0.14-0.19 where every sample takes the pixel's centre.
    const auto covered = [](double slope, double offset) {  // integral over [0, 1] of clamp(slope u + offset, 0, 1)
        std::vector<double> knots{0, 1};
        for (const double level : {0.0, 1.0})
            if (slope != 0) {
                const double u = (level - offset) / slope;
                if (u > 0 && u < 1) knots.push_back(u);
            }
        std::sort(knots.begin(), knots.end());
        const auto height = [&](double u) { return std::clamp(slope * u + offset, 0.0, 1.0); };
        double area = 0;
        for (std::size_t k = 0; k + 1 < knots.size(); ++k)
            area += (knots[k + 1] - knots[k]) * (height(knots[k]) + height(knots[k + 1])) / 2;
        return area;
    };
    for (const int count : {16, 64}) {
        const prism::ZSobolPattern sobol(count, 64, 64, 1);
        double jittered_error = 0, sobol_error = 0;
        std::vector<prism::CameraSample<Real>> grid;
        std::vector<Vec2<Real>> scratch;
        for (int y = 0; y < 64; ++y)
            for (int x = 0; x < 64; ++x) {
                prism::Random edge = prism::Random::for_pixel(x, y, 99);
                const double slope = 2 * edge.uniform<double>() - 1;
                const double offset = -std::max(slope, 0.0) + (1 + std::abs(slope)) * edge.uniform<double>();
                const bool swapped = edge.uniform<double>() < 0.5;
                const double area = covered(slope, offset);
                const auto inside = [&](Vec2<Real> p) {
                    const double u = double(swapped ? p.y : p.x), v = double(swapped ? p.x : p.y);
                    return v < slope * u + offset ? 1.0 / count : 0.0;
                };
                prism::Random stream = prism::Random::for_pixel(x, y, 5);
                prism::camera_samples(count, stream, grid, scratch);
                auto sampler = sobol.for_pixel(x, y);
                double on_grid = 0, on_net = 0;
                for (int s = 0; s < count; ++s) {
                    on_grid += inside(grid[std::size_t(s)].pixel);
                    sampler.start_sample(s);
                    on_net += inside(sampler.template uniform2<Real>());
                }
                jittered_error += (on_grid - area) * (on_grid - area);
                sobol_error += (on_net - area) * (on_net - area);
            }
        const double ratio = std::sqrt(sobol_error / jittered_error);
        MESSAGE(count, " samples: edge RMSE of ZSobol's pixel pair / the jittered grid's = ", ratio);
        CHECK(std::sqrt(jittered_error / 4096) < 0.5 / std::sqrt(count));  // below the Monte Carlo rate, sqrt(p (1 - p) / n) <= 0.5 / sqrt(n)
        CHECK(ratio < 0.95);
    }
}

TEST_CASE_TEMPLATE("Samplers: the run-time choice draws what the chosen sampler draws, bit for bit", Real, float, double) {
    static_assert(prism::PixelSampler<prism::ChosenSampler, Real>);
    static_assert(prism::SamplerPattern<prism::ChosenPattern, Real>);
    const auto same_draws = [](auto chosen, auto alone) {
        int differ = 0;
        for (int s = 0; s < 6; ++s) {
            chosen.start_sample(s);
            alone.start_sample(s);
            for (int d = 0; d < 5; ++d) {
                differ += chosen.template uniform<Real>() != alone.template uniform<Real>();
                const prism::Vec2<Real> a = chosen.template uniform2<Real>(), b = alone.template uniform2<Real>();
                differ += a != b;
                chosen.template skip<Real>(d);
                alone.template skip<Real>(d);
                differ += chosen.dimension() != alone.dimension();
            }
            chosen.seek(40);
            alone.seek(40);
            differ += chosen.template uniform<Real>() != alone.template uniform<Real>();
        }
        return differ;
    };
    const prism::SamplingLayout layout{6, 20, 10, 17, {}};
    // Patterns outlive their samplers (a temporary pattern makes none: for_pixel const&&).
    prism::SamplingLayout chosen_independent = layout, chosen_stratified = layout, chosen_sobol = layout,
                          defaulted = layout;
    chosen_independent.kind = prism::SamplerKind::independent;
    chosen_stratified.kind = prism::SamplerKind::stratified;
    chosen_sobol.kind = prism::SamplerKind::sobol;
    defaulted.kind = prism::default_sampler;  // left open, the kind is default_sampler
    const prism::ChosenPattern as_independent(chosen_independent), as_stratified(chosen_stratified),
        as_sobol(chosen_sobol), left_open(layout), as_default(defaulted);
    const prism::IndependentPattern independent(6, 17);
    const prism::StratifiedPattern stratified(6, 17);
    const prism::ZSobolPattern sobol_pattern(6, 20, 10, 17);
    for (const auto& [x, y] : {std::pair{0, 0}, std::pair{3, 9}, std::pair{19, 4}}) {
        CHECK(same_draws(as_independent.for_pixel(x, y), independent.for_pixel(x, y)) == 0);
        CHECK(same_draws(as_stratified.for_pixel(x, y), stratified.for_pixel(x, y)) == 0);
        CHECK(same_draws(as_sobol.for_pixel(x, y), sobol_pattern.for_pixel(x, y)) == 0);
        CHECK(same_draws(left_open.for_pixel(x, y), as_default.for_pixel(x, y)) == 0);
    }
    // A stream ignores seek and has no dimensions; the others go where they are sent.
    prism::IndependentSampler stream = prism::IndependentPattern(1, 3).for_pixel(2, 2), unmoved = stream;
    stream.seek(12);
    CHECK(stream.dimension() == 0);
    CHECK(stream.template uniform<Real>() == unmoved.template uniform<Real>());
    const prism::ZSobolPattern small(4, 4, 4, 3);
    prism::ZSobolSampler sobol = small.for_pixel(1, 1), walked = sobol;
    sobol.start_sample(2);
    walked.start_sample(2);
    sobol.seek(9);
    walked.template skip<Real>(9);
    CHECK(sobol.dimension() == 9);
    CHECK(sobol.template uniform2<Real>() == walked.template uniform2<Real>());
}

TEST_CASE("Samplers: names parse both ways, and a fixed pattern refuses another kind") {
    for (const prism::SamplerKind kind :
         {prism::SamplerKind::independent, prism::SamplerKind::stratified, prism::SamplerKind::sobol})
        CHECK(prism::parse_sampler(prism::sampler_name(kind)) == kind);
    CHECK_FALSE(prism::parse_sampler("halton").has_value());
    CHECK_FALSE(prism::parse_sampler("").has_value());
    CHECK_FALSE(prism::parse_sampler("Sobol").has_value());
    prism::SamplingLayout layout{4, 8, 8, 0, prism::SamplerKind::sobol};
    CHECK_NOTHROW(prism::make_pattern<prism::ZSobolPattern>(layout));
    CHECK_NOTHROW(prism::make_pattern<prism::ChosenPattern>(layout));
    CHECK_THROWS_WITH_AS(prism::make_pattern<prism::StratifiedPattern>(layout),
                         "the sampler sobol was asked for, and this renderer was compiled with stratified only",
                         std::invalid_argument);
    layout.kind.reset();
    CHECK_NOTHROW(prism::make_pattern<prism::StratifiedPattern>(layout));
    CHECK(prism::streamed(prism::make_pattern<prism::IndependentPattern>(layout)));
    CHECK_FALSE(prism::streamed(prism::make_pattern<prism::StratifiedPattern>(layout)));
    layout.kind = prism::SamplerKind::independent;
    CHECK(prism::streamed(prism::make_pattern<prism::ChosenPattern>(layout)));
    layout.kind = prism::SamplerKind::stratified;
    CHECK_FALSE(prism::streamed(prism::make_pattern<prism::ChosenPattern>(layout)));
}

TEST_CASE_TEMPLATE("Samplers: a Config that fixes its sampler renders what the run-time choice of it renders", Real, float,
                   double) {
    // A rough mirror floor under a point light and four samples a pixel: every sample draws
    // (the camera's dimensions, the glossy lobe's), so a sampler that differed would show.
    namespace scene = prism::scene;
    scene::Scene world;
    world.max_recursion_depth = 2;
    scene::Material matte;
    matte.diffuse = {0.7, 0.4, 0.2};
    scene::Material rough;
    rough.type = scene::MaterialType::mirror;
    rough.mirror = {0.8, 0.8, 0.8};
    rough.roughness = 0.3;
    world.materials = {matte, rough};
    world.spheres.push_back({"ball", 0, {0, 0, -3}, 0.8, glm::dmat4(1.0)});
    world.planes.push_back({"floor", 1, {0, -0.8, 0}, {0, 1, 0}, glm::dmat4(1.0)});
    world.point_lights.push_back({"bulb", {1, 3, -1}, {30, 30, 30}});
    scene::Camera camera;
    camera.gaze = {0, -0.2, -1};
    camera.up = {0, 1, 0};
    camera.near_left = camera.near_bottom = -0.5;
    camera.near_right = camera.near_top = 0.5;
    camera.width = camera.height = 12;
    camera.num_samples = 4;
    camera.image_name = "out.png";
    world.cameras.push_back(camera);
    using Chosen = prism::Config<Real, prism::Bvh<prism::Watertight>, prism::Lights<prism::PointLight>, prism::Features{},
                                 prism::Whitted, prism::ChosenPattern>;
    using Fixed = prism::Config<Real, prism::Bvh<prism::Watertight>, prism::Lights<prism::PointLight>, prism::Features{},
                                prism::Whitted, prism::ZSobolPattern>;
    const prism::RendererSettings sobol{prism::BackfaceCulling::triangles, prism::RayOffset::scene_epsilon, 5,
                                        prism::SamplerKind::sobol};
    const prism::Image chosen = prism::Renderer<Chosen>(world, sobol).render(world.cameras[0]);
    const prism::Image fixed = prism::Renderer<Fixed>(world, sobol).render(world.cameras[0]);
    CHECK(chosen.pixels == fixed.pixels);
    // Left open, the fixed Config renders its own sampler; another kind is refused.
    prism::RendererSettings open = sobol;
    open.sampler.reset();
    CHECK(prism::Renderer<Fixed>(world, open).render(world.cameras[0]).pixels == fixed.pixels);
    prism::RendererSettings other = sobol;
    other.sampler = prism::SamplerKind::independent;
    CHECK_THROWS_AS(prism::Renderer<Fixed>(world, other), std::invalid_argument);
    // And the sampler matters: the independent image differs.
    CHECK(prism::Renderer<Chosen>(world, other).render(world.cameras[0]).pixels != fixed.pixels);
}

TEST_CASE("Samplers: Sobol' dimension 1 by superset XORs equals it bit by bit") {
    std::uint32_t index = 0x12345678u;
    int differ = 0;
    for (int i = 0; i < 4096; ++i) {
        differ += prism::sampling::sobol_dimension1(std::uint32_t(i)) != prism::sampling::sobol_dimension1_bitwise(std::uint32_t(i));
        index = index * 1664525u + 1013904223u;
        differ += prism::sampling::sobol_dimension1(index) != prism::sampling::sobol_dimension1_bitwise(index);
    }
    CHECK(differ == 0);
    CHECK(prism::sampling::sobol_dimension1(0xffffffffu) == prism::sampling::sobol_dimension1_bitwise(0xffffffffu));
}
