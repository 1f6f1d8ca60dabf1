// Where a pixel's camera samples go: NumSamples points of the pixel, of the lens and of the
// shutter interval, each set stratified on its own and the sets shuffled against each other, so
// that no dimension repeats another's pattern (Shirley 1991; pbrt-v4's StratifiedSampler and its
// independent padding of dimensions). A square count gets a jittered k x k grid; any other count
// gets n-rooks (one sample per row and per column of an n x n grid), which stratifies both axes.
// The reconstruction filter weighs each sample by its position in the pixel.
#pragma once

#include <prism/sampling/random.hpp>
#include <prism/scene/scene.hpp>

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace prism {

template <Scalar Real>
struct CameraSample {
    Vec2<Real> pixel{0.5};  // position inside the pixel, [0, 1)^2 from its top-left corner
    Vec2<Real> lens{0.5};   // point of the aperture, [0, 1)^2
    Real time = 0;          // shutter instant, [0, 1)
};

namespace detail {

template <class T>
void shuffle(std::vector<T>& values, Random& random) {
    for (std::size_t i = values.size(); i > 1; --i) std::swap(values[i - 1], values[random.below(std::uint32_t(i))]);
}
// The stream outputs shuffle takes for n values: one below() each from n down to 2.
inline std::uint64_t shuffle_outputs(int n) { return n > 1 ? std::uint64_t(n - 1) : 0; }

// The side of stratified_2d's grid for n points, or 0 where n is not a square (n-rooks).
inline int grid_side(int n) {
    const int side = int(std::lround(std::sqrt(double(n))));
    return side * side == n ? side : 0;
}

// n stratified points of [0, 1)^2: jittered grid for square n, n-rooks otherwise.
template <Scalar Real>
void stratified_2d(int n, Random& random, std::vector<Vec2<Real>>& points) {
    points.resize(std::size_t(n));
    if (const int side = grid_side(n); side != 0) {
        for (int j = 0; j < side; ++j)
            for (int i = 0; i < side; ++i) {
                const Vec2<Real> jitter = random.uniform2<Real>();
                points[std::size_t(j * side + i)] = (Vec2<Real>(Real(i), Real(j)) + jitter) / Real(side);
            }
        return;
    }
    std::vector<int> columns(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) columns[std::size_t(i)] = i;
    shuffle(columns, random);
    for (int i = 0; i < n; ++i) {
        const Vec2<Real> jitter = random.uniform2<Real>();
        points[std::size_t(i)] = (Vec2<Real>(Real(i), Real(columns[std::size_t(i)])) + jitter) / Real(n);
    }
}
// The stream outputs stratified_2d takes for n points: two uniforms a point, and n-rooks'
// shuffle of its columns.
template <Scalar Real>
std::uint64_t stratified_2d_outputs(int n) {
    return 2 * std::uint64_t(n) * std::uint64_t(Random::outputs_per_uniform<Real>) + (grid_side(n) != 0 ? 0 : shuffle_outputs(n));
}

}  // namespace detail

// The sample of a one-sample pixel: the pixel centre, as the course's single-sample images are
// rendered; lens and time still vary between pixels (drawn in that order).
template <Scalar Real>
CameraSample<Real> centre_sample(Random& random) {
    CameraSample<Real> sample;
    sample.lens = random.uniform2<Real>();
    sample.time = random.uniform<Real>();
    return sample;
}

// The camera's dimensions of a sample drawn from a pixel sampler that is not a stream
// (sampling/sampler.hpp): the position in the pixel (0-1; the centre in a one-sample pixel, as
// centre_sample, its pair skipped), the lens point (2-3) and the shutter instant (4). The
// sampler stratifies each across the pixel's samples itself. The integrator draws from
// camera_dimensions on.
inline constexpr int camera_dimensions = 5;

// camera_sample's `reads` says which of them the render reads: the lens point only through an
// aperture, the instant only where something moves. The others are skipped, not drawn: every
// dimension has its own numbers in such a sampler, so the rest keep theirs and the image is the
// same, without the work of drawing what no one reads (the lens pair and the instant were
// about 7% of the render time on scenes/environment/latlong with ZSobol, whose first draw of a
// dimension works out a block of samples).
struct CameraReads {
    bool lens = true, time = true;
};

template <Scalar Real, class Sampler>
CameraSample<Real> camera_sample(Sampler& sampler, bool centred, CameraReads reads = {}) {
    CameraSample<Real> sample;
    if (centred) sampler.template skip<Real>(2);
    else sample.pixel = sampler.template uniform2<Real>();
    if (reads.lens) sample.lens = sampler.template uniform2<Real>();
    else sampler.template skip<Real>(2);
    if (reads.time) sample.time = sampler.template uniform<Real>();
    else sampler.template skip<Real>(1);
    return sample;
}

// Fills `samples` with the pixel's `count` camera samples from its random stream. `scratch`
// avoids reallocating per pixel. `reads` says which parts the render reads (camera_sample): a
// part it does not read is not made, and the stream steps past its draws at once
// (Random::advance), so every later draw is the one it was. For the lens points that is
// stratified_2d's draws and the shuffle's; for the instants, one draw each and the shuffle's.
// Made and thrown away, the lens points and instants of a pinhole camera in a still scene were
// two thirds of the pixels' camera sampling, 6% of hw3 cornellbox_arealight's profile.
template <Scalar Real>
void camera_samples(int count, Random& random, std::vector<CameraSample<Real>>& samples,
                    std::vector<Vec2<Real>>& scratch, CameraReads reads = {}) {
    samples.resize(std::size_t(count));
    if (count == 1) {
        samples[0] = centre_sample<Real>(random);
        return;
    }
    detail::stratified_2d(count, random, scratch);
    for (int i = 0; i < count; ++i) samples[std::size_t(i)].pixel = scratch[std::size_t(i)];
    if (reads.lens) {
        detail::stratified_2d(count, random, scratch);
        detail::shuffle(scratch, random);
        for (int i = 0; i < count; ++i) samples[std::size_t(i)].lens = scratch[std::size_t(i)];
    } else {
        random.advance(detail::stratified_2d_outputs<Real>(count) + detail::shuffle_outputs(count));
        for (int i = 0; i < count; ++i) samples[std::size_t(i)].lens = Vec2<Real>(Real(0.5));
    }
    // Time: one jittered stratum per sample, shuffled.
    if (reads.time) {
        for (int i = 0; i < count; ++i) scratch[std::size_t(i)].x = (Real(i) + random.uniform<Real>()) / Real(count);
        for (std::size_t i = std::size_t(count); i > 1; --i) std::swap(scratch[i - 1].x, scratch[random.below(std::uint32_t(i))].x);
        for (int i = 0; i < count; ++i) samples[std::size_t(i)].time = scratch[std::size_t(i)].x;
    } else {
        random.advance(std::uint64_t(count) * std::uint64_t(Random::outputs_per_uniform<Real>) + detail::shuffle_outputs(count));
        for (int i = 0; i < count; ++i) samples[std::size_t(i)].time = Real(0);
    }
}

// The reconstruction filter's weight of a sample at `pixel` (position in the pixel, [0, 1)^2).
// Gaussian: standard deviation half a pixel around the centre, so a corner sample weighs e^-1
// of a central one; each pixel averages its own samples only.
template <Scalar Real>
Real filter_weight(scene::PixelFilter filter, const Vec2<Real>& pixel) {
    if (filter == scene::PixelFilter::box) return Real(1);
    const Vec2<Real> d = pixel - Vec2<Real>(Real(0.5));
    constexpr Real sigma = Real(0.5);
    return std::exp(-glm::dot(d, d) / (2 * sigma * sigma));
}

}  // namespace prism
