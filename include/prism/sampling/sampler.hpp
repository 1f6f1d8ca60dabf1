// Where a pixel's samples draw their numbers: a sampler hands sample `index` of a pixel its
// values dimension by dimension, each use of a number (pixel position, lens, time, light choice,
// light point, BRDF lobe, roulette, per bounce) taking the next dimension in a fixed order.
// Keyed by (pixel, sample index, dimension) rather than by a running stream, a sample's numbers
// do not depend on which other samples were drawn before it, nor in which order: the property
// pbrt-v4's samplers have (Pharr, Jakob and Humphreys, 4th ed., ch. 8), which both the
// one-path-at-a-time integrators and stages over batches of paths can rely on.
//
// A sampler comes in two parts: the pattern of a render (samples per pixel, resolution, seed),
// built once, and the pixel's sampler that the pattern makes for each pixel. Three patterns:
// - IndependentPattern: each pixel's PCG32 stream (sampling/random.hpp), drawn in order; its
//   start_sample is a no-op, so the numbers are exactly those of the stream;
// - StratifiedPattern (sampling/stratified.hpp): every dimension jittered-stratified over the
//   pixel's samples, dimensions shuffled against each other;
// - ZSobolPattern (sampling/sobol.hpp): Owen-scrambled Sobol' points with the pixels in Morton
//   order, which spreads the error as blue noise (Ahmed and Wonka 2020).
#pragma once

#include <prism/math/vector.hpp>
#include <prism/sampling/random.hpp>

#include <concepts>
#include <cstdint>

namespace prism {

// What an integrator and the renderer call on a pixel's sampler. uniform() takes one dimension,
// uniform2() two; skip<Real>(n) passes n dimensions without drawing them, so that every later
// use keeps its dimension whether or not the skipped ones were needed (a point light needs no
// sample of its surface). dimension() is the next dimension to be drawn and seek(d) makes it d:
// a path tracer gives each bounce a fixed block of dimensions, so that a branch that draws less
// (a specular bounce, no Fresnel choice) does not shift every later bounce's numbers. A stream
// (IndependentSampler) has no dimensions: its draws are simply the next numbers, skip steps it
// as it always has, and seek leaves it where it is, so seeking changes no independent image.
template <class S, class Real>
concept PixelSampler = Scalar<Real> && requires(S& sampler, const S& const_sampler, int index, int count) {
    sampler.start_sample(index);  // sample `index` of the pixel, from its first dimension
    { sampler.template uniform<Real>() } -> std::same_as<Real>;
    { sampler.template uniform2<Real>() } -> std::same_as<Vec2<Real>>;
    sampler.template skip<Real>(count);
    { const_sampler.dimension() } -> std::same_as<int>;
    sampler.seek(count);
};

// A render's pattern makes each pixel's sampler; samples_per_pixel is the pixel's sample count.
template <class P, class Real>
concept SamplerPattern = requires(const P& pattern, int x, int y) {
    { pattern.for_pixel(x, y) } -> PixelSampler<Real>;
    { pattern.samples_per_pixel() } -> std::same_as<int>;
};

// Today's sampling: the pixel's PCG32 stream, each draw the next number of it whatever the
// sample, so that the samples of a pixel draw one after another, as they always have.
class IndependentSampler : public Random {
public:
    explicit constexpr IndependentSampler(const Random& stream) : Random(stream) {}
    constexpr void start_sample(int) {}
    constexpr int dimension() const { return 0; }
    constexpr void seek(int) {}
};

class IndependentPattern {
public:
    constexpr IndependentPattern(int samples_per_pixel, std::uint64_t seed)
        : samples_per_pixel_(samples_per_pixel < 1 ? 1 : samples_per_pixel), seed_(seed) {}
    constexpr IndependentSampler for_pixel(int x, int y) const {
        return IndependentSampler(Random::for_pixel(x, y, seed_));
    }
    constexpr int samples_per_pixel() const { return samples_per_pixel_; }

private:
    int samples_per_pixel_;
    std::uint64_t seed_;
};

namespace sampling {

// A hash of a key (pixel, seed, use) into 64 well-mixed bits.
constexpr std::uint64_t hash_key(std::uint64_t a, std::uint64_t b, std::uint64_t c = 0) {
    return mix_bits(a ^ mix_bits(b ^ mix_bits(c + 0x9e3779b97f4a7c15ULL)));
}

// Dimension `dimension`'s key under a base hashed once (hash_key of the pixel, seed and use): one
// round of mixing a draw instead of hash_key's three, on the base offset by the dimension times
// the golden ratio's odd constant, as SplitMix64 keys its outputs.
constexpr std::uint64_t dimension_key(std::uint64_t base, int dimension) {
    return mix_bits(base ^ (std::uint64_t(std::uint32_t(dimension)) * 0x9e3779b97f4a7c15ULL));
}

// 32 bits as a number in [0, 1) of the renderer's precision: a float keeps the top 24 bits, so
// that rounding never gives 1; a double all 32.
template <Scalar Real>
constexpr Real unit_from_bits(std::uint32_t bits) {
    if constexpr (sizeof(Real) == 4) return float(bits >> 8) * 0x1p-24f;
    else return Real(bits) * Real(0x1p-32);
}

}  // namespace sampling

}  // namespace prism
