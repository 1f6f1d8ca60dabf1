// simd/pack.hpp: max_keep and min_keep, whose exact IEEE behaviour the wide BVH's slab test relies on
// (a NaN distance constrains nothing), and sqrt, negation and >=, which the direct spheres'
// test on several rays relies on for the scalar sphere test's bits. A faster form must keep
// these bits. And select, lane by lane at every width the kernels use (clang 14 with libstdc++'s
// AVX-512 masks got it wrong: simd/pack.hpp). Widths beyond one register are two halves
// (simd/pack.hpp, needs_halves): 16 floats and 8 doubles under AVX2.
#include "same_bits.hpp"

#include <prism/simd/pack.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <limits>

using prism_test::same_bits;

namespace {

template <class T, int N>
void check_keep() {
    using Pack = prism::simd::Pack<T, N>;
    const T nan = std::numeric_limits<T>::quiet_NaN(), inf = std::numeric_limits<T>::infinity();
    // Pairs (a, b): NaN on either side, both signs of zero, infinities, ordinary values.
    const T as[] = {nan, T(1), T(0), T(-0.0), inf, -inf, T(2), T(-3), nan, T(5), T(0), T(-0.0)};
    const T bs[] = {T(1), nan, T(-0.0), T(0), T(1), T(1), T(3), T(-2), nan, T(5), T(0), T(-0.0)};
    constexpr int count = sizeof(as) / sizeof(as[0]);
    for (int start = 0; start < count; start += N) {
        alignas(64) T a[N], b[N], high[N], low[N];
        for (int i = 0; i < N; ++i) {
            a[i] = as[(start + i) % count];
            b[i] = bs[(start + i) % count];
        }
        prism::simd::max_keep(Pack::load(a), Pack::load(b)).store(high);
        prism::simd::min_keep(Pack::load(a), Pack::load(b)).store(low);
        for (int i = 0; i < N; ++i) {
            CAPTURE(a[i]);
            CAPTURE(b[i]);
            // Exactly a > b ? a : b and a < b ? a : b, to the bit: a NaN in a leaves b, equal
            // values (either zero) give b.
            CHECK(same_bits(high[i], a[i] > b[i] ? a[i] : b[i]));
            CHECK(same_bits(low[i], a[i] < b[i] ? a[i] : b[i]));
        }
    }
}

template <class T, int N>
void check_sqrt_negation_compare() {
    using Pack = prism::simd::Pack<T, N>;
    const T nan = std::numeric_limits<T>::quiet_NaN(), inf = std::numeric_limits<T>::infinity();
    const T values[] = {T(2),  T(0),   T(-0.0), inf, nan, T(-1), std::numeric_limits<T>::denorm_min(),
                        T(3e-7), T(1e30), T(0.1), T(7), T(1) + std::numeric_limits<T>::epsilon()};
    constexpr int count = sizeof(values) / sizeof(values[0]);
    for (int start = 0; start < count; start += N) {
        alignas(64) T a[N], b[N], root[N], negated[N];
        for (int i = 0; i < N; ++i) {
            a[i] = values[(start + i) % count];
            b[i] = values[(start + 3 * i + 1) % count];
        }
        sqrt(Pack::load(a)).store(root);
        (-Pack::load(a)).store(negated);
        const std::uint32_t at_least = (Pack::load(a) >= Pack::load(b)).bits();
        for (int i = 0; i < N; ++i) {
            CAPTURE(a[i]);
            CAPTURE(b[i]);
            // The same bits, but for NaNs, whose payloads may differ.
            if (std::isnan(std::sqrt(a[i]))) CHECK(std::isnan(root[i]));
            else CHECK(same_bits(root[i], std::sqrt(a[i])));
            CHECK(same_bits(negated[i], T(-a[i])));
            CHECK(bool((at_least >> i) & 1) == (a[i] >= b[i]));
        }
    }
}

template <class T, int N>
void check_select() {
    using Pack = prism::simd::Pack<T, N>;
    alignas(64) T a[N], b[N], chosen[N];
    for (int pattern = 0; pattern < 8; ++pattern) {
        for (int i = 0; i < N; ++i) {
            a[i] = T(i + 1);
            b[i] = ((i * 7 + pattern) % 3 == 0) ? T(-(i + 1)) : T(100 + i);  // a < b where b is large
        }
        const Pack pa = Pack::load(a), pb = Pack::load(b);
        select(pa < pb, pa, pb).store(chosen);
        for (int i = 0; i < N; ++i) {
            CAPTURE(N);
            CAPTURE(i);
            CHECK(same_bits(chosen[i], a[i] < b[i] ? a[i] : b[i]));
        }
    }
}

// A mask's bits (lane i is bit i), any, and its &, | and !, at widths one register holds and at
// wider ones, which are two halves (simd/pack.hpp, needs_halves) on a target without them.
template <class T, int N>
void check_mask() {
    using Pack = prism::simd::Pack<T, N>;
    alignas(64) T a[N], b[N];
    for (int pattern = 0; pattern < 12; ++pattern) {
        for (int i = 0; i < N; ++i) {
            a[i] = T((i * 5 + pattern) % 7);
            b[i] = T((i * 3 + 2 * pattern) % 5);
        }
        // Pattern 0 leaves no lane below; the last lane alone is below in pattern 1.
        if (pattern == 0)
            for (int i = 0; i < N; ++i) b[i] = T(-1);
        if (pattern == 1)
            for (int i = 0; i < N; ++i) b[i] = i == N - 1 ? T(9) : T(-1);
        const Pack pa = Pack::load(a), pb = Pack::load(b);
        std::uint32_t below = 0, equal = 0;
        for (int i = 0; i < N; ++i) {
            below |= std::uint32_t(a[i] < b[i]) << i;
            equal |= std::uint32_t(a[i] == b[i]) << i;
        }
        const std::uint32_t all = N == 32 ? ~std::uint32_t(0) : (std::uint32_t(1) << N) - 1;
        CAPTURE(N);
        CAPTURE(pattern);
        CHECK((pa < pb).bits() == below);
        CHECK((pa < pb).any() == (below != 0));
        CHECK(((pa < pb) & (pa == pb)).bits() == 0);
        CHECK(((pa < pb) | (pa == pb)).bits() == (below | equal));
        CHECK((pa <= pb).bits() == (below | equal));
        CHECK((!(pa < pb)).bits() == (~below & all));
        CHECK((pa >= pb).bits() == (~below & all));
        CHECK((pa != pb).bits() == (~equal & all));
    }
}

}  // namespace

TEST_CASE_TEMPLATE("a mask's bits, any, &, | and ! are each lane's, at every width", T, float, double) {
    check_mask<T, 4>();
    check_mask<T, 8>();
    check_mask<T, 16>();
    check_mask<T, 32>();
}

TEST_CASE_TEMPLATE("select is mask ? a : b in every lane, at every width", T, float, double) {
    check_select<T, 2>();
    check_select<T, 4>();
    check_select<T, 8>();
    check_select<T, 16>();
    check_select<T, 32>();
}

TEST_CASE_TEMPLATE("sqrt is std::sqrt's, -p and p >= q each lane's, to the bit", T, float, double) {
    check_sqrt_negation_compare<T, 4>();
    check_sqrt_negation_compare<T, 8>();
    check_sqrt_negation_compare<T, 16>();
}

TEST_CASE_TEMPLATE("max_keep and min_keep are a > b ? a : b and a < b ? a : b, NaN and signed zeros included", T,
                   float, double) {
    check_keep<T, 4>();
    check_keep<T, 8>();
    check_keep<T, 16>();
    check_keep<T, 32>();
}

namespace {

// generate: lane i holds lane(i), at every width (the split widths generate both halves).
template <class T, int N>
void check_generate() {
    using Pack = prism::simd::Pack<T, N>;
    const Pack p = Pack::generate([](int i) { return T(3 * i) - T(0.5); });
    alignas(64) T out[N];
    p.store(out);
    for (int i = 0; i < N; ++i) {
        CAPTURE(N);
        CHECK(out[i] == T(3 * i) - T(0.5));
    }
}

}  // namespace

TEST_CASE_TEMPLATE("generate puts lane(i) in lane i, at every width", T, float, double) {
    check_generate<T, 2>();
    check_generate<T, 4>();
    check_generate<T, 8>();
    check_generate<T, 16>();
    check_generate<T, 32>();
}

TEST_CASE_TEMPLATE("load_transposed: column j's lane i is row i's value j, the same bits, rows anywhere", T, float, double) {
    // Rows at scattered, unaligned places (one past an odd offset into a larger buffer), some
    // repeated, as the lanes past a batch's rays repeat its first ray; NaN and signed zeros kept.
    constexpr int N = 8;
    T buffer[N * 11 + 3];
    for (int k = 0; k < N * 11 + 3; ++k) buffer[k] = T(k) * T(1.25) - T(7);
    buffer[5] = std::numeric_limits<T>::quiet_NaN();
    buffer[14] = T(-0.0);
    const int offsets[N] = {1, 12, 23, 1, 45, 56, 67, 78};
    const T* rows[N];
    for (int i = 0; i < N; ++i) rows[i] = buffer + offsets[i];
    prism::simd::Pack<T, N> columns[N];
    prism::simd::load_transposed(rows, columns);
    for (int j = 0; j < N; ++j) {
        alignas(64) T lanes[N];
        columns[j].store(lanes);
        for (int i = 0; i < N; ++i) {
            CAPTURE(i);
            CAPTURE(j);
            CHECK(same_bits(lanes[i], rows[i][j]));
        }
    }
}
