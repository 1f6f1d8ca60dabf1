// The sampler a render uses, as a Config policy (render/config.hpp): a pattern type. Three fix
// one sampler at compile time (IndependentPattern, StratifiedPattern, ZSobolPattern); a fourth,
// ChosenPattern, takes the choice at run time (RendererSettings::sampler, `--sampler`), which is
// what the shipped renderers use: one integrator per Config instead of three, and a switch per
// draw that the branch predictor always gets right (the sampler of a render never changes).
// A Config that names no sampler gets DefaultPattern, the fixed pattern of default_sampler: a
// consumer's renderer compiles the one sampler it renders with.
#pragma once

#include <prism/math/force_inline.hpp>
#include <prism/sampling/sampler.hpp>
#include <prism/sampling/sobol.hpp>
#include <prism/sampling/stratified.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>

namespace prism {

enum class SamplerKind : std::uint8_t { independent, stratified, sobol };

// The kind a render uses where nobody chose one (RendererSettings::sampler left empty with the
// ChosenPattern policy), chosen by measurement (bench/RESULTS.md, "The samplers"): at 16 and 64
// samples a pixel, each scene at its own size, sobol leaves 0.35-0.86 of independent's error for
// 1.02-1.07 of its work, so less error at equal time on every scene measured; a one-sample pixel
// without a lens or motion draws nothing, so hw1-hw2's images are the same with either.
inline constexpr SamplerKind default_sampler = SamplerKind::sobol;

constexpr std::string_view sampler_name(SamplerKind kind) {
    constexpr std::array<std::string_view, 3> names{"independent", "stratified", "sobol"};
    return names[std::size_t(kind)];
}

inline std::optional<SamplerKind> parse_sampler(std::string_view name) {
    for (SamplerKind kind : {SamplerKind::independent, SamplerKind::stratified, SamplerKind::sobol})
        if (name == sampler_name(kind)) return kind;
    return std::nullopt;
}

// One of the three pixel samplers, chosen at run time.
class ChosenSampler {
    // f applied to the sampler of the chosen kind (defined before its callers, whose return
    // types it deduces).
    template <class Self, class F>
    static constexpr decltype(auto) visit(Self& self, F f) {
        switch (self.kind_) {
            case SamplerKind::stratified: return f(self.stratified_);
            case SamplerKind::sobol: return f(self.sobol_);
            default: return f(self.independent_);
        }
    }

public:
    explicit constexpr ChosenSampler(const IndependentSampler& sampler)
        : kind_(SamplerKind::independent), independent_(sampler) {}
    explicit constexpr ChosenSampler(const StratifiedSampler& sampler)
        : kind_(SamplerKind::stratified), stratified_(sampler) {}
    explicit constexpr ChosenSampler(const ZSobolSampler& sampler) : kind_(SamplerKind::sobol), sobol_(sampler) {}
    // The chosen sampler's own copy (ZSobolSampler's leaves its block's points behind).
    constexpr ChosenSampler(const ChosenSampler& other) : kind_(other.kind_) {
        visit(other, [&](const auto& sampler) { std::construct_at(&member(sampler), sampler); });
    }
    constexpr ChosenSampler& operator=(const ChosenSampler& other) {
        if (this != &other) std::construct_at(this, other);  // every member is trivially destroyed
        return *this;
    }

    constexpr void start_sample(int index) {
        visit(*this, [&](auto& sampler) { sampler.start_sample(index); });
    }
    // A draw: the independent sampler's (a step of its stream) and sobol's (most draws read a
    // number its block worked out already) inline at the caller; the stratified sampler's
    // hashing and sobol's working-out of a block out of line. Through visit alone, the draw was
    // a call of its own for every sampler (2% of path_diffuse's profile, `visit` for uniform2);
    // sobol's reads through that call were 2% of path_glass's instructions (bench/RESULTS.md,
    // "Sobol's cost a sample").
    template <Scalar Real>
    PRISM_FORCE_INLINE constexpr Real uniform() {
        if (kind_ == SamplerKind::independent) return independent_.template uniform<Real>();
        if (kind_ == SamplerKind::sobol) return sobol_.template uniform<Real>();
        return structured_uniform<Real>();
    }
    template <Scalar Real>
    PRISM_FORCE_INLINE constexpr Vec2<Real> uniform2() {
        if (kind_ == SamplerKind::independent) return independent_.template uniform2<Real>();
        if (kind_ == SamplerKind::sobol) return sobol_.template uniform2<Real>();
        return structured_uniform2<Real>();
    }
    template <Scalar Real>
    constexpr void skip(int count) {
        visit(*this, [&](auto& sampler) { sampler.template skip<Real>(count); });
    }
    constexpr int dimension() const {
        return visit(*this, [](const auto& sampler) { return sampler.dimension(); });
    }
    constexpr void seek(int dimension) {
        visit(*this, [&](auto& sampler) { sampler.seek(dimension); });
    }

private:
    template <Scalar Real>
    [[gnu::noinline]] constexpr Real structured_uniform() {
        return visit(*this, [](auto& sampler) { return sampler.template uniform<Real>(); });
    }
    template <Scalar Real>
    [[gnu::noinline]] constexpr Vec2<Real> structured_uniform2() {
        return visit(*this, [](auto& sampler) { return sampler.template uniform2<Real>(); });
    }

    // This sampler's member of the kind of `sampler`.
    constexpr IndependentSampler& member(const IndependentSampler&) { return independent_; }
    constexpr StratifiedSampler& member(const StratifiedSampler&) { return stratified_; }
    constexpr ZSobolSampler& member(const ZSobolSampler&) { return sobol_; }

    SamplerKind kind_;
    union {
        IndependentSampler independent_;
        StratifiedSampler stratified_;
        ZSobolSampler sobol_;
    };
};

// The render's numbers, for every pattern: its sample count, image size and seed, and the kind
// asked for (empty: the pattern's own, or default_sampler where the pattern leaves it open).
struct SamplingLayout {
    int samples_per_pixel = 1;
    int width = 1, height = 1;
    std::uint64_t seed = 0;
    std::optional<SamplerKind> kind;
};

class ChosenPattern {
public:
    explicit ChosenPattern(const SamplingLayout& layout)
        : kind_(layout.kind.value_or(default_sampler)), independent_(layout.samples_per_pixel, layout.seed),
          stratified_(layout.samples_per_pixel, layout.seed) {
        // Only when chosen: its tables are worked out as it is made.
        if (kind_ == SamplerKind::sobol) sobol_.emplace(layout.samples_per_pixel, layout.width, layout.height, layout.seed);
    }

    // As ZSobolPattern's: the pattern outlives its pixels' samplers.
    ChosenSampler for_pixel(int x, int y) const& {
        switch (kind_) {
            case SamplerKind::stratified: return ChosenSampler(stratified_.for_pixel(x, y));
            case SamplerKind::sobol: return ChosenSampler(sobol_->for_pixel(x, y));
            default: return ChosenSampler(independent_.for_pixel(x, y));
        }
    }
    ChosenSampler for_pixel(int x, int y) const&& = delete;
    int samples_per_pixel() const { return independent_.samples_per_pixel(); }
    // Whether the pixel's samples draw from one stream in order (see streamed()).
    bool streamed() const { return kind_ == SamplerKind::independent; }

private:
    SamplerKind kind_;
    IndependentPattern independent_;
    StratifiedPattern stratified_;
    std::optional<ZSobolPattern> sobol_;
};

// A pattern of the given type for a render's layout. A pattern that fixes its kind refuses
// another one, so that a renderer never renders with a sampler other than the one asked for.
template <class Pattern>
Pattern make_pattern(const SamplingLayout& layout) {
    const auto fixed = [&](SamplerKind kind) {
        if (layout.kind && *layout.kind != kind)
            throw std::invalid_argument("the sampler " + std::string(sampler_name(*layout.kind)) +
                                        " was asked for, and this renderer was compiled with " +
                                        std::string(sampler_name(kind)) + " only");
    };
    if constexpr (std::is_same_v<Pattern, ChosenPattern>) {
        return ChosenPattern(layout);
    } else if constexpr (std::is_same_v<Pattern, IndependentPattern>) {
        fixed(SamplerKind::independent);
        return IndependentPattern(layout.samples_per_pixel, layout.seed);
    } else if constexpr (std::is_same_v<Pattern, StratifiedPattern>) {
        fixed(SamplerKind::stratified);
        return StratifiedPattern(layout.samples_per_pixel, layout.seed);
    } else {
        static_assert(std::is_same_v<Pattern, ZSobolPattern>, "a sampler policy is one of the four patterns");
        fixed(SamplerKind::sobol);
        return ZSobolPattern(layout.samples_per_pixel, layout.width, layout.height, layout.seed);
    }
}

// Without the other two samplers and the switch per draw, examples/minimal compiles in 0.3-0.6 s
// less of its 12 s (bench/RESULTS.md, "Compile cost"); ZSobol's fixed pattern compiles no
// stream routes (Renderer::can_stream), so it costs no more than the independent one did.
using DefaultPattern = ZSobolPattern;
static_assert(default_sampler == SamplerKind::sobol, "DefaultPattern is default_sampler's pattern");

// Whether a pattern's pixel samplers draw each pixel's samples from one stream, one after
// another (the independent sampler): the renderer then draws the camera samples from the stream
// first, stratified across the pixel (camera/pixel_sampler.hpp), as it always has; the other
// samplers take each sample's camera sample from its own first dimensions.
template <class Pattern>
bool streamed(const Pattern& pattern) {
    if constexpr (std::is_same_v<Pattern, IndependentPattern>) return true;
    else if constexpr (requires { pattern.streamed(); }) return pattern.streamed();
    else return false;
}

}  // namespace prism
