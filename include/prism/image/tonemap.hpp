// Tone mapping: one HDR render into the 8-bit images a camera's <Tonemap> elements ask for.
// Every operator shares one pipeline, as the course defines it after Reinhard, Stark, Shirley and
// Ferwerda, "Photographic Tone Reproduction for Digital Images" (SIGGRAPH 2002):
//   Y     = 0.2126 R + 0.7152 G + 0.0722 B                  (Rec. 709 / sRGB luminance)
//   L_avg = exp(mean(log(delta + Y)))                        (log-average luminance, eq. 1)
//   L     = key / L_avg * Y                                  (exposure, eq. 2)
//   L_d   = curve(L)
//   C_out = 255 * clamp((C / Y)^saturation * L_d, 0, 1)^(1 / gamma), truncated to 8 bits
// with three curves:
//   Photographic  L (1 + L / L_white^2) / (1 + L)            (Reinhard 2002, eq. 4); L_white is the
//                 scaled luminance at the (100 - burn) percentile, and burn 0 gives L / (1 + L) (eq. 3)
//   ACES          x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)   (Narkowicz 2015, "ACES Filmic Tone
//                 Mapping Curve", fitted to the ACES reference rendering transform)
//   Filmic        h(x) / h(W), h(x) = (x (A x + C B) + D E) / (x (A x + B) + D F) - E / F   (Hable 2010,
//                 "Filmic Tonemapping Operators", Uncharted 2: A 0.15, B 0.50, C 0.10, D 0.20,
//                 E 0.02, F 0.30, W 11.2)
#pragma once

#include <prism/image/image.hpp>
#include <prism/math/vector.hpp>
#include <prism/parallel/for_each_run.hpp>
#include <prism/scene/scene.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace prism {

// The luminance of linear Rec. 709 / sRGB primaries. Measured against the course's EXR/PNG pairs
// (VeachAjar_path, burn 0): 68.8 dB with these weights, 46.5 dB with Rec. 601's and 46.6 dB
// with Reinhard's 0.27/0.67/0.06.
template <Scalar Real>
Real luminance(const Vec3<Real>& color) {
    return Real(0.2126) * color.r + Real(0.7152) * color.g + Real(0.0722) * color.b;
}

// The delta that keeps log(Y) finite where a pixel is black. It is not a detail: the course's
// renders have 2-11% black background pixels, whose log(delta) dominates the log-average, so the
// delta sets the exposure. On the seven EXR/PNG pairs of the hw6/hw7 references with black
// pixels, 1e-6 reproduces the PNGs at 65.7-69.6 dB; 1e-5 gives 28-44 dB, 1e-7 gives 29-44 dB.
inline constexpr double log_average_delta = 1e-6;

// Reinhard 2002, eq. 4; an infinite L_white is eq. 3, L / (1 + L).
template <Scalar Real>
Real photographic_curve(Real scaled_luminance, Real white_luminance) {
    const Real L = scaled_luminance;
    const Real burn = std::isinf(white_luminance) ? Real(0) : L / (white_luminance * white_luminance);
    return L * (1 + burn) / (1 + L);
}

// Narkowicz 2015, without the 0.6 pre-scale of his blog's code: the key sets the exposure here.
template <Scalar Real>
Real aces_curve(Real x) {
    return x * (Real(2.51) * x + Real(0.03)) / (x * (Real(2.43) * x + Real(0.59)) + Real(0.14));
}

namespace detail {

template <Scalar Real>
Real hable(Real x) {
    const Real A = Real(0.15), B = Real(0.50), C = Real(0.10), D = Real(0.20), E = Real(0.02), F = Real(0.30);
    return (x * (A * x + C * B) + D * E) / (x * (A * x + B) + D * F) - E / F;
}

}  // namespace detail

// Hable's Uncharted 2 curve normalised by its linear white point W = 11.2, without his exposure
// bias of 2: as for ACES, the key sets the exposure.
template <Scalar Real>
Real filmic_curve(Real x) {
    return detail::hable(x) / detail::hable(Real(11.2));
}

// Pixels per run of the tone map's passes on TBB's threads (for_each_run): 192 kB of film, so
// a course image of 512 x 512 or more is split between two threads. Each pixel's value is
// worked out alone, so the image is the same for any number of threads. On the main thread
// alone, a tone map and its PNG had taken 34 ms of each 512 x 512 camera of hw7 path_diffuse,
// after the render (bench/RESULTS.md, "Writing the images").
inline constexpr std::size_t tone_map_grain = std::size_t(1) << 14;

// Luminance of each pixel; a negative or non-finite one (a broken pixel) counts as black, so it
// cannot poison the image's average.
template <Scalar Real>
std::vector<Real> luminances(const Image& hdr) {
    std::vector<Real> values(hdr.pixels.size());
    for_each_run(values.size(), tone_map_grain, [&](std::size_t first, std::size_t end) {
        for (std::size_t i = first; i < end; ++i) {
            const Real Y = luminance(Vec3<Real>(hdr.pixels[i]));
            values[i] = (std::isfinite(Y) && Y > 0) ? Y : Real(0);
        }
    });
    return values;
}

// Reinhard 2002, eq. 1. Summed in double, in pixel order: a float sum over millions of pixels
// loses digits. The logarithms are taken side by side; the sum, in order, is the same number.
template <Scalar Real>
Real log_average_luminance(const std::vector<Real>& luminance_values, Real delta = Real(log_average_delta)) {
    if (luminance_values.empty()) return Real(0);
    std::vector<double> logs(luminance_values.size());
    for_each_run(logs.size(), tone_map_grain, [&](std::size_t first, std::size_t end) {
        for (std::size_t i = first; i < end; ++i) logs[i] = std::log(double(delta) + double(luminance_values[i]));
    });
    double sum = 0.0;
    for (const double value : logs) sum += value;
    return Real(std::exp(sum / double(luminance_values.size())));
}

// L_white: the scaled luminance that `burn_percent` of the pixels reach or exceed, so that they
// burn out to white: element floor(n (100 - burn) / 100) of the ascending order. Burn 0 (or
// less) burns nothing: L_white is infinite and the curve is L / (1 + L). The course's files say
// "1 means 1 percent of the pixels will be burned out".
template <Scalar Real>
Real white_luminance(std::vector<Real> scaled_luminances, Real burn_percent) {
    if (!(burn_percent > 0) || scaled_luminances.empty()) return infinity<Real>;
    const std::size_t n = scaled_luminances.size();
    const double position = std::floor(double(n) * (100.0 - std::min(double(burn_percent), 100.0)) / 100.0);
    const std::size_t index = std::min(n - 1, std::size_t(position));
    std::nth_element(scaled_luminances.begin(), scaled_luminances.begin() + std::ptrdiff_t(index),
                     scaled_luminances.end());
    return scaled_luminances[index];
}

// A display value in 0..1 to the 0..255 scale the 8-bit writers expect (to_8bit truncates; the
// course's PNGs are truncated too: 69.6 dB truncated, 51.6 dB rounded on cornellbox_jaroslav_diffuse).
template <Scalar Real>
Real display_level(Real value, Real gamma) {
    if (!(value > 0)) return 0;  // NaN too, so a broken pixel shows black
    return Real(255) * std::pow(std::min(value, Real(1)), 1 / gamma);
}

// Tone-maps a linear HDR image as `settings` describes; the result is on the 0..255 scale of
// write_image's PNG path (one LDR image per <Tonemap>, all from the same render). `Real` is the
// precision of the arithmetic; pixels stay float.
template <Scalar Real = double>
Image tone_map(const Image& hdr, const scene::Tonemap& settings) {
    Image ldr(hdr.width, hdr.height, Image::Unfilled{});
    const std::vector<Real> Y = luminances<Real>(hdr);
    const Real average = log_average_luminance(Y);
    const Real exposure = average > 0 ? Real(settings.key) / average : Real(0);
    std::vector<Real> scaled(Y.size());
    for_each_run(Y.size(), tone_map_grain, [&](std::size_t first, std::size_t end) {
        for (std::size_t i = first; i < end; ++i) scaled[i] = exposure * Y[i];
    });
    const Real white = settings.tone_operator == scene::TonemapOperator::photographic
                           ? white_luminance(scaled, Real(settings.burn_percent))
                           : infinity<Real>;
    const Real saturation = Real(settings.saturation), gamma = Real(settings.gamma);
    // x^1 is x exactly: where the saturation is 1 (every course file that gives one), half
    // of the pixels' powers are spared.
    const bool unit_saturation = saturation == 1;
    for_each_run(Y.size(), tone_map_grain, [&](std::size_t first, std::size_t end) {
        for (std::size_t i = first; i < end; ++i) {
            if (Y[i] <= 0) {  // black stays black
                ldr.pixels[i] = glm::vec3(0.0f);
                continue;
            }
            Real displayed = 0;
            switch (settings.tone_operator) {
                case scene::TonemapOperator::photographic: displayed = photographic_curve(scaled[i], white); break;
                case scene::TonemapOperator::aces: displayed = aces_curve(scaled[i]); break;
                case scene::TonemapOperator::filmic: displayed = filmic_curve(scaled[i]); break;
            }
            const Vec3<Real> color(hdr.pixels[i]);
            for (int c = 0; c < 3; ++c) {
                // A negative channel (a colour outside the gamut) has no real power: it shows as 0.
                const Real ratio = std::max(color[c], Real(0)) / Y[i];
                const Real saturated_ratio = unit_saturation ? ratio : std::pow(ratio, saturation);
                ldr.pixels[i][c] = float(display_level(saturated_ratio * displayed, gamma));
            }
        }
    });
    return ldr;
}

// The file a <Tonemap> writes: the stem of the camera's ImageName followed by its Extension
// (".png" appended when the Extension names no file type: "_aces" is "_aces.png"). Without an
// Extension: the ImageName itself, or for an .exr ImageName its stem + ".png".
inline bool is_exr_name(const std::filesystem::path& name) {
    std::string extension = name.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return extension == ".exr";
}

inline std::filesystem::path tone_mapped_image_name(const std::string& image_name, const scene::Tonemap& settings) {
    const std::filesystem::path name(image_name);
    if (settings.extension.empty()) return is_exr_name(name) ? std::filesystem::path(name).replace_extension(".png") : name;
    std::string file = name.stem().string() + settings.extension;
    // "x" + : an Extension that is only ".png" is a file extension, not a hidden file's name.
    if (std::filesystem::path("x" + settings.extension).extension().empty()) file += ".png";
    return name.parent_path() / file;
}

// One image file a camera writes, and which of its Tonemaps makes it (none: the raw render,
// linear for .exr, the course's clamp for .png).
struct CameraOutput {
    std::filesystem::path name;
    std::optional<std::size_t> tonemap;
};

// Every file a camera writes: an .exr ImageName holds the raw radiance and each Tonemap adds
// its PNG; a .png ImageName with Tonemaps holds the first Tonemap's image unless a Tonemap
// without Extension names it, and each Tonemap with an Extension adds its own.
inline std::vector<CameraOutput> camera_outputs(const scene::Camera& camera) {
    std::vector<CameraOutput> outputs;
    for (std::size_t t = 0; t < camera.tonemaps.size(); ++t)
        outputs.push_back({tone_mapped_image_name(camera.image_name, camera.tonemaps[t]), t});
    const std::filesystem::path own(camera.image_name);
    const bool named = std::any_of(outputs.begin(), outputs.end(), [&](const CameraOutput& o) { return o.name == own; });
    if (camera.tonemaps.empty() || is_exr_name(own)) outputs.insert(outputs.begin(), {own, std::nullopt});
    else if (!named) outputs.insert(outputs.begin(), {own, std::size_t(0)});
    return outputs;
}

}  // namespace prism
