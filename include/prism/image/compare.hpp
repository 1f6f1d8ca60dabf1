// Image comparison for the scene suite and the benchmarks: PSNR, RMSE and the share of visibly
// wrong pixels over 8-bit RGB (what the PNG files hold), and an area-averaging box filter that
// brings a full-size reference down to the size of a reduced-resolution render.
#pragma once

#include <prism/image/image.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace prism {

// Bit for bit the same radiance: what a deterministic renderer must give on every run.
inline bool same_bits(const Image& a, const Image& b) {
    return a.width == b.width && a.height == b.height &&
           std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(a.pixels[0])) == 0;
}

namespace detail {

// Mean of the squared differences over every channel value, in 8-bit levels squared.
inline double mean_square_difference(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b,
                                     const char* caller) {
    if (a.size() != b.size()) throw std::invalid_argument(std::string(caller) + ": the images differ in size");
    if (a.empty()) throw std::invalid_argument(std::string(caller) + ": empty images");
    double sum_of_squares = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const double difference = double(a[i]) - double(b[i]);
        sum_of_squares += difference * difference;
    }
    return sum_of_squares / double(a.size());
}

}  // namespace detail

// Peak signal-to-noise ratio in dB over every channel value, with 255 as the peak; infinity for
// identical images, so "equal" never hides behind a large finite number.
inline double psnr(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
    const double mean_square = detail::mean_square_difference(a, b, "psnr");
    if (mean_square == 0.0) return std::numeric_limits<double>::infinity();
    return 10.0 * std::log10(255.0 * 255.0 / mean_square);
}

// Root-mean-square difference over every channel value, in 8-bit levels (0..255): the error PSNR
// is computed from, on a scale that reads directly and is 0 for identical images.
inline double rmse(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
    return std::sqrt(detail::mean_square_difference(a, b, "rmse"));
}

// Share (0..1) of RGB pixels where any channel differs by more than `levels`: PSNR averages a
// few badly wrong pixels away, this does not.
inline double share_off_by_more_than(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b,
                                     int levels) {
    if (a.size() != b.size()) throw std::invalid_argument("share_off_by_more_than: the images differ in size");
    if (a.size() % 3 != 0) throw std::invalid_argument("share_off_by_more_than: not RGB data");
    const std::size_t pixels = a.size() / 3;
    if (pixels == 0) return 0.0;
    std::size_t off = 0;
    for (std::size_t p = 0; p < pixels; ++p)
        for (std::size_t c = 0; c < 3; ++c)
            if (std::abs(int(a[3 * p + c]) - int(b[3 * p + c])) > levels) {
                ++off;
                break;
            }
    return double(off) / double(pixels);
}

namespace detail {

struct BoxTap {
    int source;
    double weight;  // overlap length, in source pixels
};

// For each target pixel along one axis, the source pixels its footprint
// [t * source/target, (t+1) * source/target) overlaps and by how much. Computing the edges as
// t * source / target (not t * ratio) keeps them exact for integer ratios.
inline std::vector<std::vector<BoxTap>> box_taps(int source, int target) {
    std::vector<std::vector<BoxTap>> taps(static_cast<std::size_t>(target));
    for (int t = 0; t < target; ++t) {
        const double begin = double(t) * source / target;
        const double end = double(t + 1) * source / target;
        for (int s = int(std::floor(begin)); s < source && double(s) < end; ++s) {
            const double overlap = std::min(end, double(s + 1)) - std::max(begin, double(s));
            if (overlap > 0.0) taps[std::size_t(t)].push_back({s, overlap});
        }
    }
    return taps;
}

}  // namespace detail

// Resamples by area: every target pixel is the average of the source area it covers, partial
// source pixels weighted by their covered fraction, so the image mean is preserved for any ratio
// (5x5 -> 2x2 as well as 4x4 -> 2x2).
// `Source`: an Image, or anything read the same way (width, height, (x, y) -> glm::vec3), such as a
// texture's bytes (image/texels.hpp).
template <class Source = Image>
Image downsample_box(const Source& source, int width, int height) {
    if (width <= 0 || height <= 0) throw std::invalid_argument("downsample_box: target size must be positive");
    if (source.width <= 0 || source.height <= 0) throw std::invalid_argument("downsample_box: empty source image");
    const auto columns = detail::box_taps(source.width, width);
    const auto rows = detail::box_taps(source.height, height);
    Image target(width, height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            double sum[3] = {0.0, 0.0, 0.0};
            double total_weight = 0.0;
            for (const auto& row : rows[std::size_t(y)])
                for (const auto& column : columns[std::size_t(x)]) {
                    const double weight = row.weight * column.weight;
                    const glm::vec3 pixel = source(column.source, row.source);
                    for (int c = 0; c < 3; ++c) sum[c] += weight * double(pixel[c]);
                    total_weight += weight;
                }
            target(x, y) = glm::vec3(float(sum[0] / total_weight), float(sum[1] / total_weight),
                                     float(sum[2] / total_weight));
        }
    return target;
}

// Comparing radiance (HDR references): one display transform for both images, fixed by the
// reference alone. Radiance times `exposure` is clamped to [0, 1] and gamma-encoded (1/2.2) to
// 8 bits, so dark regions weigh as in a PNG. A path-traced reference's own tone-mapped PNG
// takes its key from its noisy log-average (the mean of log Y drops with noise), so a
// converged render tone-mapped by its own statistics is exposed differently; comparing radiance
// under the reference's exposure does not charge that to the render.
inline std::vector<std::uint8_t> display_8bit(const Image& radiance, double exposure) {
    std::vector<std::uint8_t> bytes;
    bytes.reserve(radiance.pixels.size() * 3);
    for (const glm::vec3& pixel : radiance.pixels)
        for (int c = 0; c < 3; ++c) {
            const double value = std::clamp(double(pixel[c]) * exposure, 0.0, 1.0);
            bytes.push_back(std::uint8_t(std::lround(255.0 * std::pow(value, 1.0 / 2.2))));
        }
    return bytes;
}

// The exposure that brings the reference's mean luminance (Rec. 709) to 0.18, the photographic
// middle grey; 1 for a black image.
inline double mean_grey_exposure(const Image& reference) {
    double sum = 0.0;
    for (const glm::vec3& pixel : reference.pixels)
        sum += 0.2126 * double(pixel.r) + 0.7152 * double(pixel.g) + 0.0722 * double(pixel.b);
    const double mean = reference.pixels.empty() ? 0.0 : sum / double(reference.pixels.size());
    return mean > 0.0 && std::isfinite(mean) ? 0.18 / mean : 1.0;
}

}  // namespace prism
