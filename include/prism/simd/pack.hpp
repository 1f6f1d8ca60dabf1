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
#include <cstdint>

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
template <class T, int N>
PRISM_SIMD_INLINE inline Pack<T, N> max_keep(Pack<T, N> a, Pack<T, N> b) { return select(a > b, a, b); }
template <class T, int N>
PRISM_SIMD_INLINE inline Pack<T, N> min_keep(Pack<T, N> a, Pack<T, N> b) { return select(a < b, a, b); }

}  // namespace prism::simd
