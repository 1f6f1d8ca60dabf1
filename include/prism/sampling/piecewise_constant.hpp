// Piecewise-constant distributions on [0, 1) and [0, 1)^2, sampled by inverting their cumulative
// distribution functions: the method of Pharr, Jakob and Humphreys, "Physically Based Rendering"
// (4th ed., sec. A.4.2: PiecewiseConstant1D and PiecewiseConstant2D; 3rd ed., sec. 13.6.7). A 2D
// table is a marginal distribution over its rows and one conditional distribution per row.
// Environment lights sample their image with it, in proportion to luminance.
#pragma once

#include <prism/math/vector.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace prism {

// n cells of width 1/n, cell i holding the value f[i]. Negative and non-finite values count as
// zero; a table that is zero everywhere becomes uniform, so sampling never divides by zero.
template <Scalar Real>
class PiecewiseConstant1D {
public:
    struct Sample {
        Real x = 0;    // in [0, 1)
        Real pdf = 0;  // density with respect to x: f(x) / integral
        std::size_t cell = 0;
    };

    PiecewiseConstant1D() : PiecewiseConstant1D(std::vector<Real>{Real(1)}) {}

    explicit PiecewiseConstant1D(std::vector<Real> function) : function_(std::move(function)) {
        if (function_.empty()) function_.assign(1, Real(1));
        for (Real& value : function_)
            if (!(value > 0) || !std::isfinite(value)) value = 0;
        const std::size_t n = function_.size();
        // Accumulated in double: a float running sum over a 1024-pixel row would drift by
        // more than the smallest cells it must keep apart.
        std::vector<double> running(n + 1, 0.0);
        for (std::size_t i = 0; i < n; ++i) running[i + 1] = running[i] + double(function_[i]) / double(n);
        integral_ = running[n];
        if (!(integral_ > 0)) {
            for (std::size_t i = 0; i <= n; ++i) running[i] = double(i) / double(n);
            integral_ = 0;
        }
        cdf_.resize(n + 1);
        const double total = running[n];
        for (std::size_t i = 0; i <= n; ++i) cdf_[i] = Real(running[i] / total);
        cdf_[n] = 1;
        // One guide entry per four cells: where the search for the start of each range of u
        // ends (Chen and Asau's guide table), so that a sample searches the few entries between
        // two guides instead of the whole table.
        const std::size_t buckets = (n + 3) / 4;
        guide_.resize(buckets + 1);
        std::size_t above = 0;
        for (std::size_t b = 0; b <= buckets; ++b) {
            const Real start = Real(b) / Real(buckets);
            while (above <= n && !(start < cdf_[above])) ++above;
            guide_[b] = std::uint32_t(above);
        }
    }

    std::size_t size() const { return function_.size(); }
    Real value(std::size_t cell) const { return function_[cell]; }
    // The integral of f over [0, 1); zero for a table that was zero everywhere (sampled
    // uniformly all the same).
    double integral() const { return integral_; }

    // The x whose CDF is u. upper_bound skips cells of zero width, so a zero-valued cell is
    // never returned.
    Sample sample(Real u) const {
        const std::size_t n = size();
        const std::size_t above = upper_bound(u);
        const std::size_t cell = std::min<std::size_t>(above > 0 ? above - 1 : 0, n - 1);
        const Real width = cdf_[cell + 1] - cdf_[cell];
        const Real offset = width > 0 ? std::clamp((u - cdf_[cell]) / width, Real(0), Real(1)) : Real(0);
        const Real x = std::min((Real(cell) + offset) / Real(n), below_one);
        return {x, density(cell), cell};
    }

    Real pdf(Real x) const { return density(cell_of(x)); }

    // The cumulative distribution at x: the inverse of sample(), so cdf(sample(u).x) == u.
    Real cdf(Real x) const {
        const std::size_t cell = cell_of(x);
        const Real offset = std::clamp(x * Real(size()) - Real(cell), Real(0), Real(1));
        return cdf_[cell] + offset * (cdf_[cell + 1] - cdf_[cell]);
    }

private:
    static constexpr Real below_one = Real(1) - std::numeric_limits<Real>::epsilon() / 2;

    // std::upper_bound(cdf_, u): the first entry above u (cdf_.size() if none), searched
    // between the guides of u's range. The guides bound the answer for every u of their range;
    // the two steps after the search put right a u that rounding put in the neighbouring range,
    // so the answer is std::upper_bound's for every u, NaN included (the end).
    std::size_t upper_bound(Real u) const {
        const std::size_t buckets = guide_.size() - 1;
        const Real scaled = u * Real(buckets);
        const std::size_t b = scaled > 0 ? std::min(std::size_t(scaled), buckets - 1) : 0;
        std::size_t above =
            std::size_t(std::upper_bound(cdf_.begin() + guide_[b], cdf_.begin() + guide_[b + 1], u) - cdf_.begin());
        while (above > 0 && u < cdf_[above - 1]) --above;
        while (above < cdf_.size() && !(u < cdf_[above])) ++above;
        return above;
    }

    std::size_t cell_of(Real x) const {
        const Real scaled = std::clamp(x, Real(0), Real(1)) * Real(size());
        return std::min(std::size_t(scaled), size() - 1);
    }

    Real density(std::size_t cell) const {
        if (integral_ > 0) return Real(double(function_[cell]) / integral_);
        return Real(1);  // the uniform fallback
    }

    std::vector<Real> function_;
    std::vector<Real> cdf_;
    std::vector<std::uint32_t> guide_;  // guide_[b]: upper_bound of b / (guide_.size() - 1)
    double integral_ = 0;
};

// width x height cells covering [0, 1)^2, row-major from y = 0: cell (column, row) holds
// function[row * width + column] and covers x in [column, column + 1) / width, y in
// [row, row + 1) / height. A sample picks the row from the marginal (the rows' integrals) with
// u.y, then the column from that row's conditional with u.x.
template <Scalar Real>
class PiecewiseConstant2D {
public:
    struct Sample {
        Vec2<Real> point{0};  // in [0, 1)^2
        Real pdf = 0;         // density with respect to area in [0, 1)^2: f(point) / integral
    };

    PiecewiseConstant2D() : PiecewiseConstant2D(std::vector<Real>{Real(1)}, 1, 1) {}

    PiecewiseConstant2D(const std::vector<Real>& function, std::size_t width, std::size_t height)
        : width_(width), height_(height) {
        assert(width > 0 && height > 0 && function.size() == width * height);
        conditional_.reserve(height);
        std::vector<Real> row_integrals(height);
        for (std::size_t row = 0; row < height; ++row) {
            conditional_.emplace_back(std::vector<Real>(function.begin() + std::ptrdiff_t(row * width),
                                                        function.begin() + std::ptrdiff_t((row + 1) * width)));
            row_integrals[row] = Real(conditional_.back().integral());
        }
        marginal_ = PiecewiseConstant1D<Real>(std::move(row_integrals));
    }

    std::size_t width() const { return width_; }
    std::size_t height() const { return height_; }
    double integral() const { return marginal_.integral(); }

    Sample sample(const Vec2<Real>& u) const {
        const auto row = marginal_.sample(u.y);
        const auto column = conditional_[row.cell].sample(u.x);
        return {Vec2<Real>(column.x, row.x), row.pdf * column.pdf};
    }

    Real pdf(const Vec2<Real>& point) const {
        const std::size_t row = std::min(std::size_t(std::clamp(point.y, Real(0), Real(1)) * Real(height_)), height_ - 1);
        return marginal_.pdf(point.y) * conditional_[row].pdf(point.x);
    }

    // The u that sample() maps to `point`: the inverse, for consistency checks.
    Vec2<Real> cdf(const Vec2<Real>& point) const {
        const std::size_t row = std::min(std::size_t(std::clamp(point.y, Real(0), Real(1)) * Real(height_)), height_ - 1);
        return {conditional_[row].cdf(point.x), marginal_.cdf(point.y)};
    }

private:
    std::size_t width_ = 1, height_ = 1;
    std::vector<PiecewiseConstant1D<Real>> conditional_;
    PiecewiseConstant1D<Real> marginal_;
};

}  // namespace prism
