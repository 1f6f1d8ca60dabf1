// Stratified sampling of every dimension: a pixel's n samples take one stratum each of every 1D
// dimension, and one cell each of an m x k grid (m = ceil(sqrt n), k = ceil(n / m)) of every 2D
// pair, jittered inside it. Which sample takes which stratum is a permutation of the sample
// indices hashed from the pixel, the dimension and the seed, so dimensions are shuffled against
// each other as pbrt-v4's StratifiedSampler pads them (Pharr, Jakob and Humphreys, 4th ed., sec.
// 8.5). A 2D pair is also stratified on each axis alone, in m k strata, as Kensler's correlated
// multi-jittered sampling arranges it (Pixar technical memo 13-01, 2013): within its cell, a
// sample's sub-column is a permutation of its row and its sub-row a permutation of its column.
#pragma once

#include <prism/sampling/sampler.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace prism {

namespace sampling {

// A permutation of [0, n) keyed by `key`: a bijection of [0, 2^b) (2^b the power of two at or
// above n, every step invertible there: xor and addition of constants, multiplication by odd
// numbers, xor with the value shifted right) applied until the value falls below n again
// (cycle walking), which restricted to [0, n) is again a bijection.
constexpr std::uint32_t permute_index(std::uint32_t i, std::uint32_t n, std::uint64_t key) {
    if (n <= 1) return 0;
    const std::uint32_t mask = std::bit_ceil(n) - 1;
    const int bits = std::bit_width(mask);
    const auto k0 = std::uint32_t(key), k1 = std::uint32_t(key >> 32);
    do {
        for (int round = 0; round < 2; ++round) {
            i = (i ^ (round ? k1 : k0)) & mask;
            i = (i * 0x9e3779b9u) & mask;  // odd
            i ^= i >> ((bits + 1) / 2);
            i = (i + (round ? k0 >> 7 : k1 >> 9)) & mask;
            i = (i * (((round ? k1 : k0) >> 3) | 1u)) & mask;
            i ^= i >> std::max(1, bits / 3);
        }
    } while (i >= n);
    return i;
}

template <Scalar Real>
constexpr Real below_one(double x) {
    return std::min(Real(x), Real(1) - std::numeric_limits<Real>::epsilon() / 2);
}

}  // namespace sampling

class StratifiedSampler {
public:
    constexpr StratifiedSampler(std::uint64_t pixel_key, int samples, std::uint64_t seed)
        : base_(sampling::hash_key(pixel_key, seed)), samples_(std::uint32_t(samples)) {
        while (columns_ * columns_ < samples_) ++columns_;
        rows_ = (samples_ + columns_ - 1) / columns_;
        inverse_samples_ = 1.0 / samples_;
        inverse_columns_ = 1.0 / columns_;
        inverse_rows_ = 1.0 / rows_;
    }

    constexpr void start_sample(int index) {
        sample_ = std::uint32_t(index) % samples_;
        dimension_ = 0;
    }

    template <Scalar Real>
    constexpr Real uniform() {
        const std::uint64_t key = dimension_key();
        const std::uint32_t stratum = sampling::permute_index(sample_, samples_, key);
        const double jitter = sampling::unit_from_bits<double>(std::uint32_t(mix_bits(key ^ sample_)));
        ++dimension_;
        return sampling::below_one<Real>((stratum + jitter) * inverse_samples_);
    }

    template <Scalar Real>
    constexpr Vec2<Real> uniform2() {
        const std::uint64_t key = dimension_key();
        const std::uint32_t cell = sampling::permute_index(sample_, samples_, key);
        const std::uint32_t column = cell % columns_, row = cell / columns_;
        const std::uint32_t sub_row = sampling::permute_index(row, rows_, mix_bits(key + 1));
        const std::uint32_t sub_column = sampling::permute_index(column, columns_, mix_bits(key + 2));
        const std::uint64_t jitter_bits = mix_bits(key ^ (std::uint64_t(sample_) << 32) ^ 0x5bd1e995u);
        const double jx = sampling::unit_from_bits<double>(std::uint32_t(jitter_bits));
        const double jy = sampling::unit_from_bits<double>(std::uint32_t(jitter_bits >> 32));
        dimension_ += 2;
        return {sampling::below_one<Real>((column + (sub_row + jx) * inverse_rows_) * inverse_columns_),
                sampling::below_one<Real>((row + (sub_column + jy) * inverse_columns_) * inverse_rows_)};
    }

    template <Scalar Real>
    constexpr void skip(int count) {
        dimension_ += count;
    }
    constexpr int dimension() const { return dimension_; }
    constexpr void seek(int dimension) { dimension_ = dimension; }

private:
    constexpr std::uint64_t dimension_key() const { return sampling::dimension_key(base_, dimension_); }

    std::uint64_t base_;  // the pixel's and seed's hash, which each dimension's key starts from
    std::uint32_t samples_;
    std::uint32_t columns_ = 1, rows_ = 1;
    // Multiplied rather than divided by: a sample's divisions waited one after another.
    double inverse_samples_ = 1, inverse_columns_ = 1, inverse_rows_ = 1;
    std::uint32_t sample_ = 0;
    int dimension_ = 0;
};

class StratifiedPattern {
public:
    constexpr StratifiedPattern(int samples_per_pixel, std::uint64_t seed)
        : samples_per_pixel_(samples_per_pixel < 1 ? 1 : samples_per_pixel), seed_(seed) {}
    constexpr StratifiedSampler for_pixel(int x, int y) const {
        const std::uint64_t pixel = (std::uint64_t(std::uint32_t(y)) << 32) | std::uint32_t(x);
        return StratifiedSampler(pixel, samples_per_pixel_, seed_);
    }
    constexpr int samples_per_pixel() const { return samples_per_pixel_; }

private:
    int samples_per_pixel_;
    std::uint64_t seed_;
};

}  // namespace prism
