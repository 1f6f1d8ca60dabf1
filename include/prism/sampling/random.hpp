// Reproducible random numbers: one PCG32 stream per pixel (O'Neill 2014, "PCG: A Family of
// Simple Fast Space-Efficient Statistically Good Algorithms for Random Number Generation"),
// selected by hashing the pixel and the render's seed. A pixel is rendered by one thread from
// start to end, so its samples do not depend on which thread renders it or in which order the
// tiles run: images are bit-identical at any thread count.
#pragma once

#include <prism/math/vector.hpp>

#include <cstdint>

namespace prism {

// SplitMix64's finaliser (Steele, Lea and Flood 2014): a bijective 64-bit mix, so neighbouring
// pixels get unrelated stream states.
constexpr std::uint64_t mix_bits(std::uint64_t v) {
    v ^= v >> 30;
    v *= 0xbf58476d1ce4e5b9ULL;
    v ^= v >> 27;
    v *= 0x94d049bb133111ebULL;
    v ^= v >> 31;
    return v;
}

class Random {
public:
    // `sequence` picks one of 2^63 independent streams, `seed` the starting point in it.
    constexpr explicit Random(std::uint64_t seed = 0, std::uint64_t sequence = 0) {
        increment_ = (sequence << 1u) | 1u;
        next_u32();
        state_ += mix_bits(seed);
        next_u32();
    }

    // The stream for pixel (x, y) of a render with the given seed.
    static constexpr Random for_pixel(int x, int y, std::uint64_t seed) {
        const std::uint64_t pixel = (std::uint64_t(std::uint32_t(y)) << 32) | std::uint32_t(x);
        return Random(mix_bits(pixel ^ mix_bits(seed)), pixel);
    }

    constexpr std::uint32_t next_u32() {
        const std::uint64_t old = state_;
        state_ = old * multiplier + increment_;
        const auto xorshifted = std::uint32_t(((old >> 18u) ^ old) >> 27u);
        const auto rotation = std::uint32_t(old >> 59u);
        return (xorshifted >> rotation) | (xorshifted << ((~rotation + 1u) & 31u));
    }

    // Uniform in [0, 1): the top 24 (float) or 53 (double) bits, so 1 is never returned even
    // after rounding to Real.
    template <Scalar Real>
    constexpr Real uniform() {
        if constexpr (sizeof(Real) == 4) return Real(next_u32() >> 8) * Real(0x1p-24);
        else return Real((std::uint64_t(next_u32()) << 21) ^ (next_u32() >> 11)) * Real(0x1p-53);
    }

    template <Scalar Real>
    constexpr Vec2<Real> uniform2() {
        const Real u = uniform<Real>();
        return {u, uniform<Real>()};
    }

    // Steps the stream past `count` uniform<Real>() draws without making them: a caller that
    // needs no sample (a point light) skips its draws this way, so that every later draw
    // (a glossy reflection's) is the one it would have been.
    // The k steps are taken as one: state m^k + increment (m^(k-1) + ... + 1), mod 2^64 as each
    // step is, so the state is the same bits. The coefficients depend on k alone and fold to
    // constants where k does; the state then waits for one multiplication, not k in a row.
    template <Scalar Real>
    constexpr void skip(int count) {
        const int steps = sizeof(Real) == 4 ? count : 2 * count;
        std::uint64_t power = 1, sum = 0;
        for (int i = 0; i < steps; ++i) {
            sum += power;
            power *= multiplier;
        }
        state_ = state_ * power + increment_ * sum;
    }

    // Uniform integer in [0, n) (Lemire's multiply-shift; the bias is below 2^-32 n).
    constexpr std::uint32_t below(std::uint32_t n) { return std::uint32_t((std::uint64_t(next_u32()) * n) >> 32); }

private:
    static constexpr std::uint64_t multiplier = 0x5851f42d4c957f2dULL;  // PCG's 64-bit LCG
    std::uint64_t state_ = 0;
    std::uint64_t increment_ = 1;
};

}  // namespace prism
