// Owen-scrambled Sobol' points with the pixels in Morton order: the design of Ahmed and Wonka,
// "Screen-Space Blue-Noise Diffusion of Monte Carlo Sampling Error via Hierarchical Ordering of
// Pixels" (SIGGRAPH Asia 2020), as pbrt-v4's ZSobolSampler uses it (Pharr, Jakob and Humphreys,
// 4th ed., sec. 8.7.7), with the index shuffled by a nested uniform scramble (Burley,
// "Practical Hash-based Owen Scrambling", JCGT 2020, sec. 5) rather than by hashed base-4 digit
// permutations.
//
// Every dimension (or pair of dimensions) is a (0, 2)-sequence: the first two Sobol' dimensions,
// each scrambled with its own seed. Sample i of pixel (x, y) is point (morton(x, y) << log2 spp)
// + i of it, so the pixel's samples are one aligned block of the sequence, which is a (0, m, 2)-net
// for 2^m samples: stratified in every elementary interval. Before it is used the index is
// shuffled by a nested uniform scramble keyed by the dimension: each bit flipped by a hash of the
// bits above it, so each pixel's block goes to another aligned block (still a net), neighbouring
// pixels (neighbours in Morton order) take distinct parts of their parent's block, and so their
// errors differ in the way blue noise does. Dimensions are padded with independent scrambles
// rather than taken from higher Sobol' dimensions, whose 2D projections are poorer.
#pragma once

#include <prism/sampling/sampler.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <memory>
#include <utility>

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

// The seed's hashes for single dimensions, pairs and the index shuffle's salt, which each
// dimension's keys start from (dimension_key): hashed once a render, by the pattern.
struct ZSobolKeys {
    std::uint64_t single, pair, salt;
    static constexpr ZSobolKeys of(std::uint64_t seed) { return {hash_key(0, seed, 1), hash_key(0, seed, 2), hash_key(0, seed, 3)}; }
};

// A dimension's keys: the index shuffle's salt and the points' scrambles (single, and the pair's
// two halves).
struct ZSobolDimension {
    std::uint64_t salt, pair;
    std::uint32_t single;
    static constexpr ZSobolDimension of(const ZSobolKeys& keys, int dimension) {
        return {dimension_key(keys.salt, dimension), dimension_key(keys.pair, dimension),
                std::uint32_t(dimension_key(keys.single, dimension))};
    }
};

// What a render's pixels share of each of the first dimensions, worked out once by its pattern
// (ZSobolSampler::tables) instead of once a pixel: the dimension's keys (three mixing rounds).
struct ZSobolTables {
    static constexpr int dimensions = 64;  // ZSobolSampler::cached_dimensions
    std::array<ZSobolDimension, dimensions> keys;
};

}  // namespace sampling

class ZSobolSampler {
public:
    // The samples of a pixel whose draws of a dimension are worked out together: the samples of
    // a pixel run one after another, and each use of a number takes the same dimension in each,
    // so a dimension's first draw in a block of `lanes` samples works out the block's points in
    // plain loops over the lanes, which the compiler vectorises, and the block's other samples
    // read theirs. Sixteen lanes, one 64-byte register of 32-bit values: at 16 samples a pixel
    // one block is the pixel, so a dimension that few of its samples reach (a deep bounce) is
    // worked out once a pixel rather than once for each half.
    static constexpr int lane_bits = 4, lanes = 1 << lane_bits;

    // `tables` (ZSobolSampler::tables of the same keys), if given, must outlive the sampler: a
    // pattern's samplers read its tables. The same points either way.
    constexpr ZSobolSampler(std::uint64_t morton, int log2_samples, const sampling::ZSobolKeys& keys,
                            const sampling::ZSobolTables* tables = nullptr)
        : morton_(morton), log2_samples_(log2_samples), keys_(keys), tables_(tables) {}

    // The keys a pattern's pixels share (sampling::ZSobolTables).
    static sampling::ZSobolTables tables(const sampling::ZSobolKeys& keys) {
        sampling::ZSobolTables made;
        for (int dimension = 0; dimension < sampling::ZSobolTables::dimensions; ++dimension)
            made.keys[std::size_t(dimension)] = sampling::ZSobolDimension::of(keys, dimension);
        return made;
    }

    // A copy draws what the original draws: it takes the pixel and the sample, and works out
    // its block's points again. Nothing else is copied (12 KB, of which a new pixel's sampler
    // holds nothing yet).
    constexpr ZSobolSampler(const ZSobolSampler& other)
        : morton_(other.morton_), log2_samples_(other.log2_samples_), keys_(other.keys_), tables_(other.tables_),
          dimension_(other.dimension_), lane_(other.lane_), block_(other.block_) {}
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
    // line, so that a draw of points already worked out is a load where the caller draws.
    [[gnu::noinline]] constexpr std::uint32_t single_worked_out() {
        std::array<std::uint32_t, lanes> uncached;
        std::array<std::uint32_t, lanes>& block = cached() ? singles_[std::size_t(dimension_)] : uncached;
        singles(dimension_keys(), block);
        if (cached()) singles_known_ |= std::uint64_t(1) << dimension_;
        return block[std::size_t(lane_)];
    }
    [[gnu::noinline]] constexpr std::pair<std::uint32_t, std::uint32_t> pair_worked_out() {
        Pairs uncached;
        Pairs& block = cached() ? pairs_[std::size_t(dimension_)] : uncached;
        pairs(dimension_keys(), block);
        if (cached()) pairs_known_ |= std::uint64_t(1) << dimension_;
        return {block.x[std::size_t(lane_)], block.y[std::size_t(lane_)]};
    }

    // The current dimension's keys: the pattern's, or worked out past its tables.
    constexpr sampling::ZSobolDimension dimension_keys() const {
        if (tables_ && cached()) return tables_->keys[std::size_t(dimension_)];
        return sampling::ZSobolDimension::of(keys_, dimension_);
    }

    // Dimension `keys`' numbers of the block's samples: as single dimensions (Sobol' dimension 0
    // of the shuffled index, which is the index reversed, so scrambled as it is), or as pairs
    // (dimensions 0 and 1, each with its key). Always all the lanes, so that each loop is a few
    // vector instructions with no remainder: with fewer than `lanes` samples a pixel, the
    // block's lanes past them are worked out and never read.
    constexpr void singles(const sampling::ZSobolDimension& keys, std::array<std::uint32_t, lanes>& bits) const {
        std::array<std::uint32_t, lanes> index;
        point_indices(keys.salt, index);
        const std::uint32_t key = keys.single;
        for (std::size_t l = 0; l < lanes; ++l) bits[l] = sampling::owen_scramble_reversed(index[l], key);
    }
    constexpr void pairs(const sampling::ZSobolDimension& keys, Pairs& block) const {
        std::array<std::uint32_t, lanes> index;
        point_indices(keys.salt, index);
        const std::uint32_t x_key = std::uint32_t(keys.pair), y_key = std::uint32_t(keys.pair >> 32);
        for (std::size_t l = 0; l < lanes; ++l) block.x[l] = sampling::owen_scramble_reversed(index[l], x_key);
        for (std::size_t l = 0; l < lanes; ++l)
            block.y[l] = sampling::owen_scramble_reversed(sampling::sobol_dimension1_reversed(index[l]), y_key);
    }

    // The Sobol' indices the dimension takes for the block's samples: each sample's index
    // (morton << log2 spp) + sample, shuffled by a nested uniform scramble keyed by the
    // dimension's salt (owen_scramble on the index as a 32-bit integer: each bit flipped by a
    // hash of the bits above it). Only the low 32 bits reach a 32-bit fraction, as in any
    // 32-bit Sobol' generator; the index's bits above them (images of more than 2^32 samples)
    // are hashed into the key, so that pixels far apart do not share points. pbrt-v4 permutes
    // each base-4 digit by a 64-bit hash of the digits above it instead, which took twice the
    // instructions here (path_glass's blocks: 104 M against 49 M), for the same error and blue
    // noise (bench/RESULTS.md, "How sobol works", "Sobol's cost a sample").
    constexpr void point_indices(std::uint64_t salt, std::array<std::uint32_t, lanes>& shuffled) const {
        const std::uint64_t first = (morton_ << log2_samples_) | std::uint64_t(block_ * lanes);
        const std::uint64_t above = first >> 32;
        const std::uint32_t key = std::uint32_t(above == 0 ? salt : mix_bits(salt ^ above));
        const std::uint32_t first_low = std::uint32_t(first);
        for (std::uint32_t l = 0; l < std::uint32_t(lanes); ++l) shuffled[l] = sampling::owen_scramble(first_low | l, key);
    }

    static constexpr int cached_dimensions = sampling::ZSobolTables::dimensions;

    std::uint64_t morton_;
    int log2_samples_;
    sampling::ZSobolKeys keys_;
    const sampling::ZSobolTables* tables_;
    int dimension_ = 0;
    int lane_ = 0;
    std::uint32_t block_ = ~std::uint32_t(0);  // the block of samples whose points pairs_ and singles_ hold
    std::uint64_t pairs_known_ = 0;    // bit d: pairs_[d] holds the block's points of dimension d
    std::uint64_t singles_known_ = 0;  // bit d: singles_[d] holds them
    // Filled dimension by dimension as the block's first sample draws it (no values before).
    std::array<Pairs, cached_dimensions> pairs_;
    std::array<std::array<std::uint32_t, lanes>, cached_dimensions> singles_;
};

// A render's ZSobol pattern: its sample count rounded up to a power of two for the index (the
// first samples_per_pixel of each pixel's block are used).
class ZSobolPattern {
public:
    ZSobolPattern(int samples_per_pixel, int /*width*/, int /*height*/, std::uint64_t seed)
        : samples_per_pixel_(std::max(1, samples_per_pixel)), keys_(sampling::ZSobolKeys::of(seed)) {
        log2_samples_ = std::bit_width(std::uint32_t(samples_per_pixel_ - 1));
        tables_ = std::make_shared<const sampling::ZSobolTables>(ZSobolSampler::tables(keys_));
    }

    // The pixel's sampler, which reads the pattern's tables: the pattern (or a copy of it)
    // outlives it, so a pattern about to end makes none (the sanitizers' build caught a test's
    // sampler drawing from its temporary pattern's freed tables).
    ZSobolSampler for_pixel(int x, int y) const& {
        return ZSobolSampler(sampling::morton_2d(std::uint32_t(x), std::uint32_t(y)), log2_samples_, keys_, tables_.get());
    }
    ZSobolSampler for_pixel(int x, int y) const&& = delete;
    int samples_per_pixel() const { return samples_per_pixel_; }

private:
    int samples_per_pixel_;
    sampling::ZSobolKeys keys_;
    int log2_samples_ = 0;
    std::shared_ptr<const sampling::ZSobolTables> tables_;  // shared by the pattern's copies
};

}  // namespace prism
