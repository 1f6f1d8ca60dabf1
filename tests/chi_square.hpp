// Pearson's chi-square test of a sampler's frequencies against the proportions it should follow:
// over a table of cells (test_environment_light.cpp's distributions), and pooled for densities
// over many cells whose expected counts are too small for the statistic (tests/test_brdf.cpp).
#pragma once

#include <doctest/doctest.h>

#include <cmath>
#include <cstddef>
#include <vector>

namespace prism_test {

// Pearson's statistic of the counts drawn from a table against the table's proportions, over
// its non-zero cells; a zero cell must never be drawn.
template <class Real>
double pearson_chi_square(const std::vector<Real>& table, const std::vector<int>& hits, int count) {
    double total = 0;
    for (const Real value : table) total += double(value);
    double chi_square = 0;
    for (std::size_t i = 0; i < table.size(); ++i) {
        if (table[i] == 0) {
            CHECK(hits[i] == 0);
            continue;
        }
        const double expected = count * double(table[i]) / total;
        chi_square += (hits[i] - expected) * (hits[i] - expected) / expected;
    }
    return chi_square;
}

struct ChiSquare {
    double statistic = 0;
    int degrees_of_freedom = 0;
};

// Pearson's statistic with the cells whose expected count is below `minimum_expected` pooled into
// one (the usual rule: the statistic follows chi-square only when every expected count is about 5
// or more; Jakob's Mitsuba chi2 tests pool the same way). `probabilities` are each cell's share
// of the density, integrated numerically: a cell on the edge of the support may come out zero
// and still be drawn, so zero cells join the pool rather than being required empty.
inline ChiSquare pooled_chi_square(const std::vector<double>& probabilities, const std::vector<int>& hits, int count,
                                   double minimum_expected = 5) {
    ChiSquare result;
    double pooled_expected = 0;
    long long pooled_hits = 0;
    int cells = 0;
    for (std::size_t i = 0; i < probabilities.size(); ++i) {
        const double expected = probabilities[i] * count;
        if (expected < minimum_expected) {
            pooled_expected += expected;
            pooled_hits += hits[i];
            continue;
        }
        result.statistic += (hits[i] - expected) * (hits[i] - expected) / expected;
        ++cells;
    }
    if (pooled_expected > 0) {
        result.statistic += (double(pooled_hits) - pooled_expected) * (double(pooled_hits) - pooled_expected) / pooled_expected;
        ++cells;
    }
    result.degrees_of_freedom = cells - 1;
    return result;
}

// The 99.9% quantile of chi-square with k degrees of freedom, by Wilson and Hilferty's cube-root
// approximation (1931; within 1% of the exact quantile for k >= 10): a correct sampler exceeds it
// once in a thousand seeds, and the tests' seeds are fixed.
inline double chi_square_quantile_999(int k) {
    const double z = 3.090232;  // the standard normal's 99.9% quantile
    const double a = 2.0 / (9.0 * k);
    return k * std::pow(1 - a + z * std::sqrt(a), 3.0);
}

}  // namespace prism_test
