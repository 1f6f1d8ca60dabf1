// Reproducible random numbers: one PCG32 stream per pixel (O'Neill 2014, "PCG: A Family of
// Simple Fast Space-Efficient Statistically Good Algorithms for Random Number Generation"),
// selected by hashing the pixel and the render's seed. A pixel is rendered by one thread from
// start to end, so its samples do not depend on which thread renders it or in which order the
// tiles run: images are bit-identical at any thread count.
#pragma once

#include <prism/math/vector.hpp>

#include <array>
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
    constexpr explicit Random(std::uint64_t seed = 0, std::uint64_t sequence = 0)
        : state_(seeded(sequence_increment(sequence), seed)), increment_(sequence_increment(sequence)) {}

    // The stream for pixel (x, y) of a render with the given seed.
    static constexpr Random for_pixel(int x, int y, std::uint64_t seed) {
        const std::uint64_t pixel = (std::uint64_t(std::uint32_t(y)) << 32) | std::uint32_t(x);
        return Random(mix_bits(pixel ^ mix_bits(seed)), pixel);
    }

    // The streams of pixels (x0 + i, y), i < N, each as for_pixel makes it, stepped past
    // `skipped` draws of Real (skip) and then drawn once (draws[i], uniform<Real>), in plain
    // loops over the lanes that the compiler vectorises: the same integer operations, mod 2^64,
    // as stream by stream (which took 6% of hw1 simple_shading's instructions: two SplitMix
    // rounds and four LCG steps a pixel, one after another).
    template <Scalar Real, std::size_t N>
    static void for_row(int x0, int y, std::uint64_t seed, int skipped, std::array<Random, N>& streams,
                        std::array<Real, N>& draws) {
        const std::uint64_t mixed_seed = mix_bits(seed);
        const Jump jump = jump_of(sizeof(Real) == 4 ? skipped : 2 * skipped);
        std::array<std::uint64_t, N> state, increment;
        for (std::size_t i = 0; i < N; ++i) {
            const std::uint64_t pixel =
                (std::uint64_t(std::uint32_t(y)) << 32) | std::uint32_t(x0 + static_cast<int>(i));
            increment[i] = sequence_increment(pixel);
            // for_pixel's stream, then the skipped steps as one.
            state[i] = seeded(increment[i], mix_bits(pixel ^ mixed_seed)) * jump.power + increment[i] * jump.sum;
        }
        if constexpr (sizeof(Real) == 4) {
            for (std::size_t i = 0; i < N; ++i) {
                const std::uint64_t old = state[i];
                state[i] = old * multiplier + increment[i];
                draws[i] = unit_float(output(old));  // uniform<float>
            }
        }
        for (std::size_t i = 0; i < N; ++i) {
            streams[i].state_ = state[i];
            streams[i].increment_ = increment[i];
        }
        // A double takes two outputs, in the order uniform's expression evaluates them.
        if constexpr (sizeof(Real) == 8)
            for (std::size_t i = 0; i < N; ++i) draws[i] = streams[i].template uniform<Real>();
    }

    constexpr std::uint32_t next_u32() {
        const std::uint64_t old = state_;
        state_ = old * multiplier + increment_;
        return output(old);
    }

    // Uniform in [0, 1): the top 24 (float) or 53 (double) bits, so 1 is never returned even
    // after rounding to Real.
    template <Scalar Real>
    constexpr Real uniform() {
        if constexpr (sizeof(Real) == 4) return unit_float(next_u32());
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
        const Jump jump = jump_of(sizeof(Real) == 4 ? count : 2 * count);
        state_ = state_ * jump.power + increment_ * jump.sum;
    }

    // Steps the stream past `steps` outputs (next_u32 calls) in O(log steps) multiplications:
    // the LCG's k steps as one (Brown, "Random Number Generation with Arbitrary Strides", 1994,
    // as PCG's pcg32_advance takes it), mod 2^64 as each step is, so the state is the same bits.
    // For a count known only at run time, where skip's coefficients would take k steps to make.
    constexpr void advance(std::uint64_t steps) {
        std::uint64_t power = 1, sum = 0, step_power = multiplier, step_sum = increment_;
        for (; steps != 0; steps >>= 1) {
            if (steps & 1) {
                power *= step_power;
                sum = sum * step_power + step_sum;
            }
            step_sum = (step_power + 1) * step_sum;
            step_power *= step_power;
        }
        state_ = power * state_ + sum;
    }
    // How many outputs uniform<Real>() takes.
    template <Scalar Real>
    static constexpr int outputs_per_uniform = sizeof(Real) == 4 ? 1 : 2;

    // Uniform integer in [0, n) (Lemire's multiply-shift; the bias is below 2^-32 n).
    constexpr std::uint32_t below(std::uint32_t n) { return std::uint32_t((std::uint64_t(next_u32()) * n) >> 32); }

private:
    static constexpr std::uint64_t multiplier = 0x5851f42d4c957f2dULL;  // PCG's 64-bit LCG

    static constexpr std::uint64_t sequence_increment(std::uint64_t sequence) { return (sequence << 1u) | 1u; }

    // The state the constructor starts from: a step from state 0 (which leaves the increment),
    // the mixed seed added, a step.
    static constexpr std::uint64_t seeded(std::uint64_t increment, std::uint64_t seed) {
        return (increment + mix_bits(seed)) * multiplier + increment;
    }

    // A float in [0, 1) from an output's top 24 bits.
    static constexpr float unit_float(std::uint32_t bits) { return float(bits >> 8) * 0x1p-24f; }

    // PCG's XSH RR output of the state before a step.
    static constexpr std::uint32_t output(std::uint64_t old) {
        const auto xorshifted = std::uint32_t(((old >> 18u) ^ old) >> 27u);
        const auto rotation = std::uint32_t(old >> 59u);
        return (xorshifted >> rotation) | (xorshifted << ((~rotation + 1u) & 31u));
    }

    // k steps of the LCG as one: state m^k + increment (m^(k-1) + ... + 1).
    struct Jump {
        std::uint64_t power = 1, sum = 0;
    };
    static constexpr Jump jump_of(int steps) {
        Jump jump;
        for (int i = 0; i < steps; ++i) {
            jump.sum += jump.power;
            jump.power *= multiplier;
        }
        return jump;
    }

    std::uint64_t state_ = 0;
    std::uint64_t increment_ = 1;
};

}  // namespace prism
