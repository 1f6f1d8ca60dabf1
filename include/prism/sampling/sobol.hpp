// Owen-scrambled Sobol' points with the pixels in Morton order: the design of Ahmed and Wonka,
// "Screen-Space Blue-Noise Diffusion of Monte Carlo Sampling Error via Hierarchical Ordering of
// Pixels" (SIGGRAPH Asia 2020), as pbrt-v4's ZSobolSampler uses it (Pharr, Jakob and Humphreys,
// 4th ed., sec. 8.7.7).
//
// Every dimension (or pair of dimensions) is a (0, 2)-sequence: the first two Sobol' dimensions,
// each scrambled with its own seed. Sample i of pixel (x, y) is point (morton(x, y) << log2 spp)
// + i of it, so the pixel's samples are one aligned block of the sequence, which is a (0, m, 2)-net
// for 2^m samples: stratified in every elementary interval. Before it is used the index has its
// base-4 digits shuffled, each by one of the 24 permutations of {0, 1, 2, 3} chosen by a hash of
// the digits above it and of the dimension: neighbouring pixels (neighbours in Morton order) take
// different parts of the sequence, and so their errors differ in the way blue noise does, while
// each pixel's block stays a block. Dimensions are padded with independent scrambles rather than
// taken from higher Sobol' dimensions, whose 2D projections are poorer.
#pragma once

#include <prism/sampling/sampler.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>

namespace prism {

namespace sampling {

constexpr std::uint32_t reverse_bits(std::uint32_t v) {
    v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
    v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
    v = ((v >> 4) & 0x0f0f0f0fu) | ((v & 0x0f0f0f0fu) << 4);
    v = ((v >> 8) & 0x00ff00ffu) | ((v & 0x00ff00ffu) << 8);
    return (v >> 16) | (v << 16);
}

// The first Sobol' dimension of point `index`, as 32 bits of a fraction: the van der Corput
// sequence in base 2 (its generator matrix is the identity).
constexpr std::uint32_t sobol_dimension0(std::uint32_t index) { return reverse_bits(index); }

// The second: its generator matrix is Pascal's triangle mod 2, whose column k (the direction
// number of index bit k) is column k-1 XOR itself shifted one place down.
constexpr std::uint32_t sobol_dimension1_bitwise(std::uint32_t index) {
    std::uint32_t result = 0;
    for (std::uint32_t direction = 0x80000000u; index != 0; index >>= 1, direction ^= direction >> 1)
        if (index & 1) result ^= direction;
    return result;
}

// The same by bytes, bit-reversed (as owen_scramble_reversed takes it): the matrix is linear over
// GF(2), so the index's four bytes contribute independently, each looked up in a table of its 256
// values (4 KB in all). One bit at a time, a sample's dimension 1 waited for up to 32 dependent
// steps (with the index shuffle, a quarter of a path-traced render's time).
constexpr std::array<std::array<std::uint32_t, 256>, 4> sobol_dimension1_tables() {
    std::array<std::array<std::uint32_t, 256>, 4> tables{};
    for (std::uint32_t byte = 0; byte < 4; ++byte)
        for (std::uint32_t value = 0; value < 256; ++value)
            tables[byte][value] = reverse_bits(sobol_dimension1_bitwise(value << (8 * byte)));
    return tables;
}
inline constexpr std::array<std::array<std::uint32_t, 256>, 4> sobol_dimension1_table = sobol_dimension1_tables();

constexpr std::uint32_t sobol_dimension1_reversed(std::uint32_t index) {
    return sobol_dimension1_table[0][index & 0xff] ^ sobol_dimension1_table[1][(index >> 8) & 0xff] ^
           sobol_dimension1_table[2][(index >> 16) & 0xff] ^ sobol_dimension1_table[3][index >> 24];
}
constexpr std::uint32_t sobol_dimension1(std::uint32_t index) { return reverse_bits(sobol_dimension1_reversed(index)); }

// A nested uniform (Owen) scramble of a 32-bit fraction by hashing (Burley, "Practical Hash-based
// Owen Scrambling", JCGT 2020): on the bit-reversed value, additions and multiplications carry
// only towards higher bits, so each digit of the fraction is flipped by a function of the digits
// before it and the seed alone. That permutes the elementary intervals at every level, so a net
// stays a net.
// owen_scramble of a fraction given bit-reversed (its first digit in bit 0): Sobol' dimension 0 of
// index i is i reversed, so its scramble needs no reversal on the way in.
constexpr std::uint32_t owen_scramble_reversed(std::uint32_t v, std::uint32_t seed) {
    v ^= v * 0x3d20adeau;
    v += seed;
    v *= (seed >> 16) | 1u;
    v ^= v * 0x05526c56u;
    v ^= v * 0x53a22864u;
    return reverse_bits(v);
}
constexpr std::uint32_t owen_scramble(std::uint32_t v, std::uint32_t seed) {
    return owen_scramble_reversed(reverse_bits(v), seed);
}

// Morton order: x's bits in the even places, y's in the odd.
constexpr std::uint64_t morton_2d(std::uint32_t x, std::uint32_t y) {
    const auto spread = [](std::uint64_t v) {
        v &= 0xffffffffULL;
        v = (v | (v << 16)) & 0x0000ffff0000ffffULL;
        v = (v | (v << 8)) & 0x00ff00ff00ff00ffULL;
        v = (v | (v << 4)) & 0x0f0f0f0f0f0f0f0fULL;
        v = (v | (v << 2)) & 0x3333333333333333ULL;
        v = (v | (v << 1)) & 0x5555555555555555ULL;
        return v;
    };
    return spread(x) | (spread(y) << 1);
}

// The 24 permutations of {0, 1, 2, 3}, in lexicographic order.
constexpr std::array<std::array<std::uint8_t, 4>, 24> base4_permutations() {
    std::array<std::array<std::uint8_t, 4>, 24> all{};
    std::array<std::uint8_t, 4> p{0, 1, 2, 3};
    for (auto& permutation : all) {
        permutation = p;
        std::next_permutation(p.begin(), p.end());
    }
    return all;
}
// At namespace scope, so that it is one table in memory, not built on the stack by every call.
inline constexpr std::array<std::array<std::uint8_t, 4>, 24> base4_permutation_table = base4_permutations();

// The seed's hashes for single dimensions, pairs and the index shuffle's salt, which each
// dimension's keys start from (dimension_key): hashed once a render, by the pattern.
struct ZSobolKeys {
    std::uint64_t single, pair, salt;
    static constexpr ZSobolKeys of(std::uint64_t seed) { return {hash_key(0, seed, 1), hash_key(0, seed, 2), hash_key(0, seed, 3)}; }
};

}  // namespace sampling

class ZSobolSampler {
public:
    constexpr ZSobolSampler(std::uint64_t morton, int log2_samples, int base4_digits, const sampling::ZSobolKeys& keys)
        : morton_(morton), log2_samples_(log2_samples), base4_digits_(base4_digits), keys_(keys) {}

    constexpr void start_sample(int index) {
        index_ = (morton_ << log2_samples_) | std::uint64_t(std::uint32_t(index));
        dimension_ = 0;
    }

    template <Scalar Real>
    constexpr Real uniform() {
        const PixelDimension& known = pixel_dimension();
        // Dimension 0 of the index is the index reversed: scrambled as it is.
        const std::uint32_t bits = sampling::owen_scramble_reversed(point_index(known), known.single_key);
        ++dimension_;
        return sampling::unit_from_bits<Real>(bits);
    }

    template <Scalar Real>
    constexpr Vec2<Real> uniform2() {
        const PixelDimension& known = pixel_dimension();
        const std::uint32_t index = point_index(known);
        const std::uint32_t x = sampling::owen_scramble_reversed(index, std::uint32_t(known.pair_key));
        const std::uint32_t y = sampling::owen_scramble_reversed(sampling::sobol_dimension1_reversed(index),
                                                                 std::uint32_t(known.pair_key >> 32));
        dimension_ += 2;
        return {sampling::unit_from_bits<Real>(x), sampling::unit_from_bits<Real>(y)};
    }

    template <Scalar Real>
    constexpr void skip(int count) {
        dimension_ += count;
    }
    constexpr int dimension() const { return dimension_; }
    constexpr void seek(int dimension) { dimension_ = dimension; }

private:
    // What a dimension's draws share across the pixel's samples: its keys (one mixing round
    // each, dimension_key), and the shuffle of every index digit made of the pixel's bits, with
    // the highest digit made of the sample's bits, whose permutation is chosen by the pixel's
    // bits alone. Worked out once a pixel and dimension (for the first cached_dimensions), each
    // sample then hashes only its lower digits: at 16 samples a pixel, one hash a draw instead of
    // four (the keys, the salt and two digits).
    struct PixelDimension {
        std::uint64_t salt = 0, pair_key = 0;
        std::uint32_t single_key = 0;
        std::uint32_t pixel_digits = 0;  // only the low 32 bits of the index reach a point
        std::uint8_t top = 0;            // the top sample digit's permutation, or the base-2 flip
    };

    // The Sobol' index the current dimension takes for the current sample: the sample's index
    // with its base-4 digits shuffled, from the top, each by a permutation chosen by a hash of
    // the (original) digits above it, the dimension and the seed. With an odd log2 of the
    // sample count the lowest digit is base 2, flipped by a hash bit. Only the low 32 bits reach
    // a 32-bit fraction (sobol_dimension0/1), as in any 32-bit Sobol' generator.
    constexpr std::uint32_t point_index(const PixelDimension& known) const {
        const bool odd = (log2_samples_ & 1) != 0;
        int digit = first_pixel_digit() - 1;
        std::uint64_t shuffled = known.pixel_digits;
        if (digit >= lowest_base4_digit()) {
            shuffled |= permuted_digit(digit, known.top);
            for (--digit; digit >= lowest_base4_digit(); --digit) shuffled |= shuffled_digit(digit, known.salt);
            if (odd) shuffled |= (index_ & 1) ^ base2_flip(known.salt);
        } else if (odd) {
            shuffled |= (index_ & 1) ^ known.top;
        }
        return std::uint32_t(shuffled);
    }

    // The lowest base-4 digit made of the pixel's bits alone (every digit below holds sample bits).
    constexpr int first_pixel_digit() const { return (log2_samples_ + 1) / 2; }
    // The lowest base-4 digit: 1 where an odd log2 of the sample count leaves a base-2 digit below.
    constexpr int lowest_base4_digit() const { return log2_samples_ & 1; }
    constexpr int digit_shift(int digit) const { return 2 * digit - (log2_samples_ & 1); }
    // The base-2 digit's flip (odd log2 of the sample count): a hash bit of the digits above it.
    constexpr std::uint64_t base2_flip(std::uint64_t salt) const { return mix_bits((index_ >> 1) ^ salt) >> 63; }

    // Which of the 24 permutations shuffles base-4 digit `digit`: a hash of the digits above it.
    constexpr std::uint8_t permutation_of(int digit, std::uint64_t salt) const {
        const int shift = digit_shift(digit);
        const std::uint64_t above = shift + 2 >= 64 ? 0 : index_ >> (shift + 2);
        return std::uint8_t((mix_bits(above ^ salt) >> 40) % 24);
    }
    constexpr std::uint64_t permuted_digit(int digit, std::uint8_t permutation) const {
        const int shift = digit_shift(digit);
        return std::uint64_t(sampling::base4_permutation_table[permutation][(index_ >> shift) & 3]) << shift;
    }
    // Base-4 digit `digit` of the index, shuffled, in its place.
    constexpr std::uint64_t shuffled_digit(int digit, std::uint64_t salt) const {
        return permuted_digit(digit, permutation_of(digit, salt));
    }

    constexpr PixelDimension shared_by_samples(int dimension) const {
        PixelDimension known;
        known.salt = sampling::dimension_key(keys_.salt, dimension);
        known.single_key = std::uint32_t(sampling::dimension_key(keys_.single, dimension));
        known.pair_key = sampling::dimension_key(keys_.pair, dimension);
        std::uint64_t shuffled = 0;
        for (int digit = base4_digits_ - 1; digit >= first_pixel_digit(); --digit) shuffled |= shuffled_digit(digit, known.salt);
        known.pixel_digits = std::uint32_t(shuffled);
        const int top_digit = first_pixel_digit() - 1;
        if (top_digit >= lowest_base4_digit()) known.top = permutation_of(top_digit, known.salt);
        else if (log2_samples_ & 1) known.top = std::uint8_t(base2_flip(known.salt));
        return known;
    }

    constexpr const PixelDimension& pixel_dimension() {
        if (dimension_ < 0 || dimension_ >= cached_dimensions) {
            uncached_ = shared_by_samples(dimension_);
            return uncached_;
        }
        const std::uint64_t bit = std::uint64_t(1) << dimension_;
        if (!(known_ & bit)) {
            cache_[std::size_t(dimension_)] = shared_by_samples(dimension_);
            known_ |= bit;
        }
        return cache_[std::size_t(dimension_)];
    }

    static constexpr int cached_dimensions = 64;

    std::uint64_t morton_;
    int log2_samples_, base4_digits_;
    sampling::ZSobolKeys keys_;
    std::uint64_t index_ = 0;
    int dimension_ = 0;
    std::uint64_t known_ = 0;  // bit d: cache_[d] holds dimension d's
    std::array<PixelDimension, cached_dimensions> cache_;
    PixelDimension uncached_;
};

// A render's ZSobol pattern: its sample count rounded up to a power of two for the index (the
// first samples_per_pixel of each pixel's block are used), and enough base-4 digits for the
// larger side of the image rounded up to a power of two.
class ZSobolPattern {
public:
    ZSobolPattern(int samples_per_pixel, int width, int height, std::uint64_t seed)
        : samples_per_pixel_(std::max(1, samples_per_pixel)), keys_(sampling::ZSobolKeys::of(seed)) {
        log2_samples_ = std::bit_width(std::uint32_t(samples_per_pixel_ - 1));
        const int side = std::max({1, width, height});
        const int log2_side = std::bit_width(std::uint32_t(side - 1));
        base4_digits_ = log2_side + (log2_samples_ + 1) / 2;
    }

    ZSobolSampler for_pixel(int x, int y) const {
        return ZSobolSampler(sampling::morton_2d(std::uint32_t(x), std::uint32_t(y)), log2_samples_, base4_digits_, keys_);
    }
    int samples_per_pixel() const { return samples_per_pixel_; }

private:
    int samples_per_pixel_;
    sampling::ZSobolKeys keys_;
    int log2_samples_ = 0, base4_digits_ = 0;
};

}  // namespace prism
