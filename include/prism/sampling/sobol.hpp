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
#include <memory>
#include <utility>
#include <vector>

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

// The same bit-reversed (as owen_scramble_reversed takes it), in five steps. Bit j of the
// fraction is the XOR of the index bits k with C(k, j) odd, which by Lucas' theorem are the k
// whose binary digits include j's: a XOR over the supersets of j among the 32 bit positions. Over
// the five bits of a position, one at a time, each position takes the XOR with the position that
// has that bit too: a shift, a mask and a XOR each, in any lane of a vector. One bit at a time, a
// sample's dimension 1 waited for up to 32 dependent steps; by bytes from tables (4 KB), it was
// four loads that vectors can only gather one by one.
constexpr std::uint32_t sobol_dimension1_reversed(std::uint32_t index) {
    index ^= (index >> 1) & 0x55555555u;
    index ^= (index >> 2) & 0x33333333u;
    index ^= (index >> 4) & 0x0f0f0f0fu;
    index ^= (index >> 8) & 0x00ff00ffu;
    index ^= (index >> 16) & 0x0000ffffu;
    return index;
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

// The 24 permutations of {0, 1, 2, 3}, in lexicographic order, a byte each (two bits a digit):
// the digit a permutation makes of digit d is bits 2d and 2d + 1 of its byte. ZSobolSampler's
// blocks pack the bytes their lanes need into one word, from which each lane shifts its own.
constexpr std::array<std::uint8_t, 24> base4_permutations() {
    std::array<std::uint8_t, 24> bytes{};
    std::array<std::uint8_t, 4> p{0, 1, 2, 3};
    for (std::size_t permutation = 0; permutation < 24; ++permutation) {
        for (std::size_t digit = 0; digit < 4; ++digit) bytes[permutation] |= std::uint8_t(p[digit] << (2 * digit));
        std::next_permutation(p.begin(), p.end());
    }
    return bytes;
}
inline constexpr std::array<std::uint8_t, 24> base4_permutation_bytes = base4_permutations();

// Permutation `permutation` (0-23) as its byte.
constexpr std::uint32_t base4_permutation_byte(std::uint32_t permutation) { return base4_permutation_bytes[permutation]; }
// Digit `digit` (0-3) under permutation `permutation` (0-23).
constexpr std::uint32_t permute_base4(std::uint32_t permutation, std::uint32_t digit) {
    return (base4_permutation_byte(permutation) >> (2 * digit)) & 3;
}

// The seed's hashes for single dimensions, pairs and the index shuffle's salt, which each
// dimension's keys start from (dimension_key): hashed once a render, by the pattern.
struct ZSobolKeys {
    std::uint64_t single, pair, salt;
    static constexpr ZSobolKeys of(std::uint64_t seed) { return {hash_key(0, seed, 1), hash_key(0, seed, 2), hash_key(0, seed, 3)}; }
};

// What a render's pixels share of each of the first dimensions, worked out once by its pattern
// (ZSobolSampler::tables) instead of once a pixel: the dimension's keys (three mixing rounds),
// and its shuffle of the index's top base-4 digits (at most 4), which depends on the pixel's
// Morton prefix alone: up to 256 prefixes a dimension, where each pixel hashed each of those
// digits for each dimension it drew (4 of the 9 pixel digits of a 512 x 512 image).
struct ZSobolTables {
    struct Keys {
        std::uint64_t salt, pair;
        std::uint32_t single;
    };
    static constexpr int dimensions = 64;  // ZSobolSampler::cached_dimensions
    std::array<Keys, dimensions> keys;
    int first_digit = 0;  // the lowest digit whose shuffle `top_digits` holds
    int prefix_shift = 0;  // index >> prefix_shift is the prefix of those digits
    std::uint32_t prefixes = 0;
    std::vector<std::uint32_t> top_digits;  // [dimension * prefixes + prefix]: the shuffled digits
};

}  // namespace sampling

class ZSobolSampler {
public:
    // The samples of a pixel whose draws of a dimension are worked out together: the samples of
    // a pixel run one after another, and each use of a number takes the same dimension in each,
    // so a dimension's first draw in a block of `lanes` samples works out the block's points in
    // plain loops over the lanes, which the compiler vectorises, and the block's other samples
    // read theirs. One sample at a time, each draw waited for its own chain of hashes, bit
    // reversals and multiplications: 14% of hw7 path_glass's render and 22% of
    // scenes/environment/latlong's with this sampler (perf, 16 and 256 samples).
    // Sixteen lanes, one 64-byte register of 32-bit values: at 16 samples a pixel one block is
    // the pixel, so a dimension that few of its samples reach (a deep bounce) is worked out once
    // a pixel rather than once for each half; blocks of 8 took 3% longer on path_glass.
    static constexpr int lane_bits = 4, lanes = 1 << lane_bits;
    static_assert(lane_bits <= 4, "a base-4 digit's permutations for the lanes (2^(lane_bits - 2)) are packed a byte each in 32 bits");

    // `tables` (ZSobolSampler::tables of the same keys, sample count and digits), if given,
    // must outlive the sampler: a pattern's samplers read its tables. The same points either way.
    constexpr ZSobolSampler(std::uint64_t morton, int log2_samples, int base4_digits, const sampling::ZSobolKeys& keys,
                            const sampling::ZSobolTables* tables = nullptr)
        : morton_(morton), log2_samples_(log2_samples), base4_digits_(base4_digits), keys_(keys), tables_(tables) {}

    // The tables a pattern's pixels share (sampling::ZSobolTables).
    static sampling::ZSobolTables tables(const sampling::ZSobolKeys& keys, int log2_samples, int base4_digits) {
        sampling::ZSobolTables made;
        const ZSobolSampler layout(0, log2_samples, base4_digits, keys);
        made.first_digit = std::max(layout.first_pixel_digit(), base4_digits - 4);
        made.prefix_shift = std::max(0, layout.digit_shift(made.first_digit));
        made.prefixes = made.first_digit < base4_digits ? std::uint32_t(1) << (2 * (base4_digits - made.first_digit)) : 0;
        made.top_digits.resize(std::size_t(made.prefixes) * sampling::ZSobolTables::dimensions);
        std::vector<std::uint32_t> above, shuffled;
        for (int dimension = 0; dimension < sampling::ZSobolTables::dimensions; ++dimension) {
            sampling::ZSobolTables::Keys& keyed = made.keys[std::size_t(dimension)];
            keyed.salt = sampling::dimension_key(keys.salt, dimension);
            keyed.single = std::uint32_t(sampling::dimension_key(keys.single, dimension));
            keyed.pair = sampling::dimension_key(keys.pair, dimension);
            // Digit by digit from the top, each prefix's shuffle from its parent's: a digit's
            // permutation depends on the digits above it alone, so one hash serves the four
            // values of the digit (85 hashes a dimension for 4 digits, not 1,024).
            if (made.prefixes == 0) continue;
            above.assign(1, 0);
            for (int digit = base4_digits - 1; digit >= made.first_digit; --digit) {
                const int shift = layout.digit_shift(digit);
                shuffled.resize(above.size() * 4);
                for (std::size_t parent = 0; parent < above.size(); ++parent) {
                    const std::uint64_t index = shift + 2 >= 64 ? 0 : std::uint64_t(parent) << (shift + 2);
                    const std::uint32_t permutation = permutation_above(index, shift, keyed.salt);
                    for (std::uint32_t value = 0; value < 4; ++value)
                        shuffled[4 * parent + value] =
                            above[parent] | (shift < 32 ? sampling::permute_base4(permutation, value) << shift : 0);
                }
                std::swap(above, shuffled);
            }
            std::copy(above.begin(), above.end(), made.top_digits.begin() + std::ptrdiff_t(dimension) * made.prefixes);
        }
        return made;
    }

    // A copy draws what the original draws: it takes the pixel, the sample and the shared parts
    // of the dimensions worked out so far, and works out its block's points again. Nothing else
    // is copied (16 KB, of which a new pixel's sampler holds nothing yet: copying the 2 KB of
    // shared parts whole was 480 instructions a pixel).
    constexpr ZSobolSampler(const ZSobolSampler& other)
        : morton_(other.morton_), log2_samples_(other.log2_samples_), base4_digits_(other.base4_digits_),
          keys_(other.keys_), tables_(other.tables_), dimension_(other.dimension_), lane_(other.lane_), block_(other.block_),
          known_(other.known_) {
        for (std::uint64_t left = known_; left != 0; left &= left - 1) {
            const auto d = std::size_t(std::countr_zero(left));
            cache_[d] = other.cache_[d];
        }
    }
    constexpr ZSobolSampler& operator=(const ZSobolSampler& other) {
        if (this != &other) std::construct_at(this, other);  // every member is trivially destroyed
        return *this;
    }

    constexpr void start_sample(int index) {
        const std::uint32_t sample = std::uint32_t(index);
        const std::uint32_t block = sample / lanes;
        if (block != block_) {
            block_ = block;
            pairs_known_ = singles_known_ = 0;
        }
        lane_ = int(sample % lanes);
        dimension_ = 0;
    }

    template <Scalar Real>
    constexpr Real uniform() {
        const std::uint32_t bits =
            known(singles_known_) ? singles_[std::size_t(dimension_)][std::size_t(lane_)] : single_worked_out();
        ++dimension_;
        return sampling::unit_from_bits<Real>(bits);
    }

    template <Scalar Real>
    constexpr Vec2<Real> uniform2() {
        const auto [x, y] = known(pairs_known_) ? std::pair(pairs_[std::size_t(dimension_)].x[std::size_t(lane_)],
                                                            pairs_[std::size_t(dimension_)].y[std::size_t(lane_)])
                                                : pair_worked_out();
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
    // block of samples then hashes only the digits its samples differ in (point_indices).
    // No member initialisers: the cache's 64 entries are written as their dimensions are first
    // drawn (shared_by_samples sets every member), not zeroed for each pixel's sampler.
    struct PixelDimension {
        std::uint64_t salt, pair_key;
        std::uint32_t single_key;
        std::uint32_t pixel_digits;  // only the low 32 bits of the index reach a point
        std::uint8_t top;            // the top sample digit's permutation, or the base-2 flip
    };

    // A block's points of one dimension taken as pairs, lane by lane.
    struct Pairs {
        std::array<std::uint32_t, lanes> x, y;
    };

    // Whether the draw is kept in the block's points (dimensions below cached_dimensions).
    constexpr bool cached() const { return std::uint32_t(dimension_) < std::uint32_t(cached_dimensions); }  // negatives wrap past it
    // Whether the block's points of the current dimension are worked out (`mask`: singles_known_
    // or pairs_known_).
    constexpr bool known(std::uint64_t mask) const { return cached() && ((mask >> dimension_) & 1); }

    // A draw whose block has not worked out its dimension yet: the block's points, kept for its
    // other samples, or for a dimension past cached_dimensions, worked out and not kept. Out of
    // line, so that a draw of points already worked out is a load where the caller draws (one
    // draw in six on hw7 path_glass at 16 samples works a block out).
    [[gnu::noinline]] constexpr std::uint32_t single_worked_out() {
        std::array<std::uint32_t, lanes> uncached;
        std::array<std::uint32_t, lanes>& block = cached() ? singles_[std::size_t(dimension_)] : uncached;
        singles(pixel_dimension(), block);
        if (cached()) singles_known_ |= std::uint64_t(1) << dimension_;
        return block[std::size_t(lane_)];
    }
    [[gnu::noinline]] constexpr std::pair<std::uint32_t, std::uint32_t> pair_worked_out() {
        Pairs uncached;
        Pairs& block = cached() ? pairs_[std::size_t(dimension_)] : uncached;
        pairs(pixel_dimension(), block);
        if (cached()) pairs_known_ |= std::uint64_t(1) << dimension_;
        return {block.x[std::size_t(lane_)], block.y[std::size_t(lane_)]};
    }

    // Dimension `known`'s numbers of the block's samples: as single dimensions (Sobol'
    // dimension 0 of the shuffled index, which is the index reversed, so scrambled as it is), or
    // as pairs (dimensions 0 and 1, each with its key). Always all the lanes, so that each loop
    // is a few vector instructions with no remainder: with fewer than `lanes` samples a pixel,
    // the block's lanes past them are worked out and never read.
    constexpr void singles(const PixelDimension& known, std::array<std::uint32_t, lanes>& bits) const {
        std::array<std::uint32_t, lanes> index;
        point_indices(known, index);
        const std::uint32_t key = known.single_key;  // read once: `bits` could alias `known`
        for (std::size_t l = 0; l < lanes; ++l) bits[l] = sampling::owen_scramble_reversed(index[l], key);
    }
    constexpr void pairs(const PixelDimension& known, Pairs& block) const {
        std::array<std::uint32_t, lanes> index;
        point_indices(known, index);
        const std::uint32_t x_key = std::uint32_t(known.pair_key), y_key = std::uint32_t(known.pair_key >> 32);  // read once
        for (std::size_t l = 0; l < lanes; ++l) block.x[l] = sampling::owen_scramble_reversed(index[l], x_key);
        for (std::size_t l = 0; l < lanes; ++l)
            block.y[l] = sampling::owen_scramble_reversed(sampling::sobol_dimension1_reversed(index[l]), y_key);
    }

    // The Sobol' indices the dimension takes for the block's samples: each sample's index with
    // its base-4 digits shuffled, from the top, each by a permutation chosen by a hash of the
    // (original) digits above it, the dimension and the seed. With an odd log2 of the sample
    // count the lowest digit is base 2, flipped by a hash bit. Only the low 32 bits reach a
    // 32-bit fraction (sobol_dimension0/1), as in any 32-bit Sobol' generator.
    // The block's samples differ only in their lowest lane_bits bits, so a digit above those is
    // the block's and is shuffled once for all of them; a digit within them is shuffled lane by
    // lane, by a permutation that depends on at most the lane's bits 2 and 3 (four hashes), and
    // the base-2 digit's flip on its bits 1 to 3 (eight). Lane by lane, every digit took a hash:
    // a block of 256-sample pixels hashed 48 times where 6 hashes are needed.
    constexpr void point_indices(const PixelDimension& known, std::array<std::uint32_t, lanes>& shuffled) const {
        const std::uint64_t first = (morton_ << log2_samples_) | std::uint64_t(block_ * lanes);
        std::uint32_t block_digits = known.pixel_digits;
        std::array<std::uint32_t, lanes> lane_digits{};
        const int top = first_pixel_digit() - 1;
        // Lanes are indexed in 32 bits (the index's low 32 bits are all that reach a point), so
        // that each lane loop below is a few 8-lane vector instructions.
        const std::uint32_t first_low = std::uint32_t(first);
        for (int digit = top; digit >= lowest_base4_digit(); --digit) {
            const int shift = digit_shift(digit);
            if (shift >= lane_bits) {
                const std::uint32_t permutation = digit == top ? known.top : permutation_above(first, shift, known.salt);
                block_digits |= permuted_digit(first, shift, permutation);
                continue;
            }
            // The permutations of the lanes: the digits above this one differ from lane to lane
            // only in the lane bits above it (bits shift + 2 and up), so `variants` hashes, whose
            // permutations' bytes are packed in one word; lane l takes byte l >> above by a shift
            // of its own, where an array of bytes would be gathered lane by lane (GCC then left
            // the loop scalar: 310 instructions a block at 16 samples).
            const int above = shift + 2;
            const std::uint32_t variants = above >= lane_bits ? 1 : std::uint32_t(1) << (lane_bits - above);
            std::uint32_t packed = 0;
            for (std::uint32_t v = 0; v < variants; ++v)
                packed |= sampling::base4_permutation_byte(
                              digit == top ? known.top : permutation_above(first | (std::uint64_t(v) << above), shift, known.salt))
                          << (8 * v);
            // Not unrolled: unrolled, its lanes were left as scalar code.
#pragma GCC unroll 1
            for (std::uint32_t l = 0; l < std::uint32_t(lanes); ++l) {
                const std::uint32_t value = ((first_low | l) >> shift) & 3;
                lane_digits[l] |= ((packed >> (8 * (l >> above) + 2 * value)) & 3) << shift;
            }
        }
        if (log2_samples_ & 1) {
            if (top >= lowest_base4_digit()) {
                // The base-2 digit's flip hashes the lane's bits above bit 0: a bit for each pair
                // of lanes.
                std::uint32_t flips = 0;
                for (std::uint32_t v = 0; v < std::uint32_t(lanes / 2); ++v)
                    flips |= std::uint32_t(base2_flip(first | (std::uint64_t(v) << 1), known.salt)) << v;
                for (std::uint32_t l = 0; l < std::uint32_t(lanes); ++l) lane_digits[l] |= (l & 1) ^ ((flips >> (l >> 1)) & 1);
            } else {
                for (std::uint32_t l = 0; l < std::uint32_t(lanes); ++l) lane_digits[l] |= ((first_low | l) & 1) ^ known.top;
            }
        }
        for (std::size_t l = 0; l < lanes; ++l) shuffled[l] = block_digits | lane_digits[l];
    }

    // The lowest base-4 digit made of the pixel's bits alone (every digit below holds sample bits).
    constexpr int first_pixel_digit() const { return (log2_samples_ + 1) / 2; }
    // The lowest base-4 digit: 1 where an odd log2 of the sample count leaves a base-2 digit below.
    constexpr int lowest_base4_digit() const { return log2_samples_ & 1; }
    constexpr int digit_shift(int digit) const { return 2 * digit - (log2_samples_ & 1); }
    // The base-2 digit's flip (odd log2 of the sample count): a hash bit of the digits above it.
    static constexpr std::uint64_t base2_flip(std::uint64_t index, std::uint64_t salt) {
        return mix_bits((index >> 1) ^ salt) >> 63;
    }

    // Which of the 24 permutations shuffles the base-4 digit at `shift` of `index`: a hash of the
    // digits above it.
    static constexpr std::uint32_t permutation_above(std::uint64_t index, int shift, std::uint64_t salt) {
        const std::uint64_t above = shift + 2 >= 64 ? 0 : index >> (shift + 2);
        return std::uint32_t(mix_bits(above ^ salt) >> 40) % 24;
    }
    static constexpr std::uint32_t permuted_digit(std::uint64_t index, int shift, std::uint32_t permutation) {
        return sampling::permute_base4(permutation, std::uint32_t(index >> shift) & 3) << shift;
    }

    // Digits [first, last) of `index`, shuffled as every sample of its pixel shuffles them
    // (each digit's hash depends on the digits above it, not on their shuffle); digits at or
    // past bit 32 never reach a point.
    // Only the digits that reach are hashed, one after another: a lane for each of 16 digits had
    // AVX2 emulate 64-bit multiplications for every lane, reaching or not (images of up to 2^10
    // pixels a side at 16 samples use 10).
    constexpr std::uint32_t shuffled_digits(std::uint64_t index, int first, int last, std::uint64_t salt) const {
        std::uint32_t digits = 0;
        for (int digit = first; digit < last && digit_shift(digit) < 32; ++digit) {
            const int shift = digit_shift(digit);
            digits |= permuted_digit(index, shift, permutation_above(index, shift, salt));
        }
        return digits;
    }

    constexpr PixelDimension shared_by_samples(int dimension) const {
        PixelDimension known;  // every member set below
        const std::uint64_t index = morton_ << log2_samples_;
        const std::uint64_t prefix = tables_ ? index >> tables_->prefix_shift : 0;
        if (tables_ && std::uint32_t(dimension) < std::uint32_t(sampling::ZSobolTables::dimensions) &&
            prefix < tables_->prefixes) {
            const sampling::ZSobolTables::Keys& keyed = tables_->keys[std::size_t(dimension)];
            known.salt = keyed.salt;
            known.single_key = keyed.single;
            known.pair_key = keyed.pair;
            known.pixel_digits = tables_->top_digits[std::size_t(dimension) * tables_->prefixes + std::size_t(prefix)] |
                                 shuffled_digits(index, first_pixel_digit(), tables_->first_digit, known.salt);
        } else {
            known.salt = sampling::dimension_key(keys_.salt, dimension);
            known.single_key = std::uint32_t(sampling::dimension_key(keys_.single, dimension));
            known.pair_key = sampling::dimension_key(keys_.pair, dimension);
            known.pixel_digits = shuffled_digits(index, first_pixel_digit(), base4_digits_, known.salt);
        }
        known.top = 0;
        const int top_digit = first_pixel_digit() - 1;
        if (top_digit >= lowest_base4_digit()) known.top = std::uint8_t(permutation_above(index, digit_shift(top_digit), known.salt));
        else if (log2_samples_ & 1) known.top = std::uint8_t(base2_flip(index, known.salt));
        return known;
    }

    constexpr const PixelDimension& pixel_dimension() {
        if (!cached()) {
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

    static constexpr int cached_dimensions = sampling::ZSobolTables::dimensions;

    std::uint64_t morton_;
    int log2_samples_, base4_digits_;
    sampling::ZSobolKeys keys_;
    const sampling::ZSobolTables* tables_;
    int dimension_ = 0;
    int lane_ = 0;
    std::uint32_t block_ = ~std::uint32_t(0);  // the block of samples whose points pairs_ and singles_ hold
    std::uint64_t known_ = 0;          // bit d: cache_[d] holds dimension d's
    std::uint64_t pairs_known_ = 0;    // bit d: pairs_[d] holds the block's points of dimension d
    std::uint64_t singles_known_ = 0;  // bit d: singles_[d] holds them
    std::array<PixelDimension, cached_dimensions> cache_;
    PixelDimension uncached_;
    // Filled dimension by dimension as the block's first sample draws it (no values before).
    std::array<Pairs, cached_dimensions> pairs_;
    std::array<std::array<std::uint32_t, lanes>, cached_dimensions> singles_;
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
        tables_ = std::make_shared<const sampling::ZSobolTables>(ZSobolSampler::tables(keys_, log2_samples_, base4_digits_));
    }

    // The pixel's sampler, which reads the pattern's tables: the pattern (or a copy of it)
    // outlives it, so a pattern about to end makes none (the sanitizers' build caught a test's
    // sampler drawing from its temporary pattern's freed tables).
    ZSobolSampler for_pixel(int x, int y) const& {
        return ZSobolSampler(sampling::morton_2d(std::uint32_t(x), std::uint32_t(y)), log2_samples_, base4_digits_, keys_,
                             tables_.get());
    }
    ZSobolSampler for_pixel(int x, int y) const&& = delete;
    int samples_per_pixel() const { return samples_per_pixel_; }

private:
    int samples_per_pixel_;
    sampling::ZSobolKeys keys_;
    int log2_samples_ = 0, base4_digits_ = 0;
    std::shared_ptr<const sampling::ZSobolTables> tables_;  // shared by the pattern's copies
};

}  // namespace prism
