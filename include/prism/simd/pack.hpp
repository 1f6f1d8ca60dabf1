// The one SIMD layer of prism: Pack<T, N>, N lanes of float or double, and its Mask. The wide
// BVH's node and leaf tests are written against it; every other header stays scalar.
// Where libstdc++'s std::experimental::simd exists (GCC 11 and later, on x86-64, ARM and
// POWER), a Pack is a stdx::simd of the ABI that fits N lanes (one AVX register for 8 floats
// or 4 doubles under -mavx2, two SSE or NEON registers otherwise); elsewhere, or with
// PRISM_SIMD_SCALAR defined, it is a plain array whose loops the compiler may vectorise itself.
// Both give bit-identical results: every operation is one IEEE operation per lane, and prism
// builds with -ffp-contract=off so no compiler fuses a multiply and an add (a fused edge
// function would no longer be the exact negation of its neighbour's, and the watertight test
// would leak). See README "SIMD" for the measurements behind the choice.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <type_traits>

#if defined(__FMA__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#endif

#if !defined(PRISM_SIMD_SCALAR) && defined(__GLIBCXX__) && __has_include(<experimental/simd>)
#include <experimental/simd>
#define PRISM_SIMD_STDX 1
#endif

// Every operation is forced inline: each is one instruction or two, and a call costs more (GCC
// left the slab test's max_keep and min_keep out of line, 3.7% of a course primary profile).
#if defined(__GNUC__) || defined(__clang__)
#define PRISM_SIMD_INLINE [[gnu::always_inline]]
#else
#define PRISM_SIMD_INLINE
#endif

namespace prism::simd {

#ifdef PRISM_SIMD_STDX
namespace stdx = std::experimental;

template <class T, int N>
struct Mask {
    using Native = stdx::simd_mask<T, stdx::simd_abi::deduce_t<T, N>>;
    Native native;

    PRISM_SIMD_INLINE friend Mask operator&(Mask a, Mask b) { return {a.native && b.native}; }
    PRISM_SIMD_INLINE friend Mask operator|(Mask a, Mask b) { return {a.native || b.native}; }
    PRISM_SIMD_INLINE friend Mask operator!(Mask a) { return {!a.native}; }
    PRISM_SIMD_INLINE bool any() const { return stdx::any_of(native); }
    // Lane i is bit i. __to_bitset is libstdc++'s own (a movmsk on x86).
    PRISM_SIMD_INLINE std::uint32_t bits() const { return std::uint32_t(native.__to_bitset().to_ulong()); }
};

template <class T, int N>
struct Pack {
    using Native = stdx::simd<T, stdx::simd_abi::deduce_t<T, N>>;
    static_assert(Native::size() == std::size_t(N));
    Native native;

    PRISM_SIMD_INLINE static Pack broadcast(T value) { return {Native(value)}; }
    PRISM_SIMD_INLINE static Pack load(const T* values) { return {Native(values, stdx::element_aligned)}; }
    // N unsigned bytes, each converted exactly to T (a quantised plane, accel/wide_bvh_tree.hpp):
    // through a byte simd, GCC emits one widening load and one conversion (vpmovzxbd, vcvtdq2ps),
    // where a lane-by-lane generator converted each byte on its own.
    PRISM_SIMD_INLINE static Pack load_bytes(const std::uint8_t* bytes) {
        const stdx::simd<std::uint8_t, stdx::simd_abi::deduce_t<std::uint8_t, N>> narrow(bytes, stdx::element_aligned);
        return {stdx::static_simd_cast<Native>(narrow)};
    }
    PRISM_SIMD_INLINE void store(T* values) const { native.copy_to(values, stdx::element_aligned); }

    PRISM_SIMD_INLINE friend Pack operator+(Pack a, Pack b) { return {a.native + b.native}; }
    PRISM_SIMD_INLINE friend Pack operator-(Pack a, Pack b) { return {a.native - b.native}; }
    PRISM_SIMD_INLINE friend Pack operator*(Pack a, Pack b) { return {a.native * b.native}; }
    PRISM_SIMD_INLINE friend Pack operator/(Pack a, Pack b) { return {a.native / b.native}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator<(Pack a, Pack b) { return {a.native < b.native}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator<=(Pack a, Pack b) { return {a.native <= b.native}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator>(Pack a, Pack b) { return {a.native > b.native}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator==(Pack a, Pack b) { return {a.native == b.native}; }
    PRISM_SIMD_INLINE friend Mask<T, N> operator!=(Pack a, Pack b) { return {a.native != b.native}; }
    // mask ? a : b, lane by lane.
    PRISM_SIMD_INLINE friend Pack select(Mask<T, N> mask, Pack a, Pack b) {
        stdx::where(mask.native, b.native) = a.native;
        return b;
    }
};

#else

template <class T, int N>
struct Mask {
    std::array<bool, N> lanes;

    PRISM_SIMD_INLINE friend Mask operator&(Mask a, Mask b) { return combine(a, b, [](bool x, bool y) { return x && y; }); }
    PRISM_SIMD_INLINE friend Mask operator|(Mask a, Mask b) { return combine(a, b, [](bool x, bool y) { return x || y; }); }
    PRISM_SIMD_INLINE friend Mask operator!(Mask a) {
        for (bool& lane : a.lanes) lane = !lane;
        return a;
    }
    PRISM_SIMD_INLINE bool any() const { return bits() != 0; }
    PRISM_SIMD_INLINE std::uint32_t bits() const {
        std::uint32_t result = 0;
        for (int i = 0; i < N; ++i) result |= std::uint32_t(lanes[i]) << i;
        return result;
    }

private:
    template <class Op>
    static Mask combine(Mask a, const Mask& b, Op op) {
        for (int i = 0; i < N; ++i) a.lanes[i] = op(a.lanes[i], b.lanes[i]);
        return a;
    }
};

template <class T, int N>
struct Pack {
    std::array<T, N> lanes;

    PRISM_SIMD_INLINE static Pack broadcast(T value) {
        Pack result;
        result.lanes.fill(value);
        return result;
    }
    PRISM_SIMD_INLINE static Pack load(const T* values) {
        Pack result;
        for (int i = 0; i < N; ++i) result.lanes[i] = values[i];
        return result;
    }
    PRISM_SIMD_INLINE static Pack load_bytes(const std::uint8_t* bytes) {
        Pack result;
        for (int i = 0; i < N; ++i) result.lanes[i] = T(bytes[i]);
        return result;
    }
    PRISM_SIMD_INLINE void store(T* values) const {
        for (int i = 0; i < N; ++i) values[i] = lanes[i];
    }

    PRISM_SIMD_INLINE friend Pack operator+(Pack a, Pack b) { return map(a, b, [](T x, T y) { return x + y; }); }
    PRISM_SIMD_INLINE friend Pack operator-(Pack a, Pack b) { return map(a, b, [](T x, T y) { return x - y; }); }
    PRISM_SIMD_INLINE friend Pack operator*(Pack a, Pack b) { return map(a, b, [](T x, T y) { return x * y; }); }
    PRISM_SIMD_INLINE friend Pack operator/(Pack a, Pack b) { return map(a, b, [](T x, T y) { return x / y; }); }
    PRISM_SIMD_INLINE friend Mask<T, N> operator<(Pack a, Pack b) { return compare(a, b, [](T x, T y) { return x < y; }); }
    PRISM_SIMD_INLINE friend Mask<T, N> operator<=(Pack a, Pack b) { return compare(a, b, [](T x, T y) { return x <= y; }); }
    PRISM_SIMD_INLINE friend Mask<T, N> operator>(Pack a, Pack b) { return compare(a, b, [](T x, T y) { return x > y; }); }
    PRISM_SIMD_INLINE friend Mask<T, N> operator==(Pack a, Pack b) { return compare(a, b, [](T x, T y) { return x == y; }); }
    PRISM_SIMD_INLINE friend Mask<T, N> operator!=(Pack a, Pack b) { return compare(a, b, [](T x, T y) { return x != y; }); }
    PRISM_SIMD_INLINE friend Pack select(Mask<T, N> mask, Pack a, Pack b) {
        for (int i = 0; i < N; ++i) b.lanes[i] = mask.lanes[i] ? a.lanes[i] : b.lanes[i];
        return b;
    }

private:
    template <class Op>
    static Pack map(Pack a, const Pack& b, Op op) {
        for (int i = 0; i < N; ++i) a.lanes[i] = op(a.lanes[i], b.lanes[i]);
        return a;
    }
    template <class Op>
    static Mask<T, N> compare(const Pack& a, const Pack& b, Op op) {
        Mask<T, N> result;
        for (int i = 0; i < N; ++i) result.lanes[i] = op(a.lanes[i], b.lanes[i]);
        return result;
    }
};

#endif

// a > b ? a : b and a < b ? a : b, lane by lane: a NaN in `a` leaves `b`, which is what the
// slab test needs (a NaN slab distance, 0 * inf on a slab plane, constrains nothing).
// a * b + c rounded once, lane by lane. Where the product is exact (a quantised plane: a byte
// times a power of two) it equals a * b + c in two operations, bit for bit, in one instruction
// and one latency instead of two; prism's -ffp-contract=off forbids the compiler to fuse them.
template <class T, int N>
PRISM_SIMD_INLINE inline Pack<T, N> fused_multiply_add(Pack<T, N> a, Pack<T, N> b, Pack<T, N> c) {
#if defined(PRISM_SIMD_STDX) && defined(__FMA__)
    using Native = typename Pack<T, N>::Native;
    if constexpr (std::is_same_v<T, float> && requires(Native x) { static_cast<__m256>(x); })
        return {Native(_mm256_fmadd_ps(static_cast<__m256>(a.native), static_cast<__m256>(b.native), static_cast<__m256>(c.native)))};
    else if constexpr (std::is_same_v<T, double> && requires(Native x) { static_cast<__m256d>(x); })
        return {Native(_mm256_fmadd_pd(static_cast<__m256d>(a.native), static_cast<__m256d>(b.native), static_cast<__m256d>(c.native)))};
#if defined(__AVX512F__)
    else if constexpr (std::is_same_v<T, float> && requires(Native x) { static_cast<__m512>(x); })
        return {Native(_mm512_fmadd_ps(static_cast<__m512>(a.native), static_cast<__m512>(b.native), static_cast<__m512>(c.native)))};
    else if constexpr (std::is_same_v<T, double> && requires(Native x) { static_cast<__m512d>(x); })
        return {Native(_mm512_fmadd_pd(static_cast<__m512d>(a.native), static_cast<__m512d>(b.native), static_cast<__m512d>(c.native)))};
#endif
#endif
    alignas(64) T x[N], y[N], z[N];
    a.store(x);
    b.store(y);
    c.store(z);
    for (int i = 0; i < N; ++i) x[i] = std::fma(x[i], y[i], z[i]);
    return Pack<T, N>::load(x);
}

template <class T, int N>
PRISM_SIMD_INLINE inline Pack<T, N> max_keep(Pack<T, N> a, Pack<T, N> b) { return select(a > b, a, b); }
template <class T, int N>
PRISM_SIMD_INLINE inline Pack<T, N> min_keep(Pack<T, N> a, Pack<T, N> b) { return select(a < b, a, b); }

}  // namespace prism::simd
